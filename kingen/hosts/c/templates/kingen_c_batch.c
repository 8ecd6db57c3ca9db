/* kingen's batch driver for C host libraries: the library's functions called from C over a
 * whole batch, through pointers, so that verify and bench measure the library, not Python;
 * and each call timed singly on the monotonic clock (bench's median and worst call). */
#define _POSIX_C_SOURCE 199309L
#include <time.h>

typedef int (*kingen_inverse_fn)(const void *geometry, const double *pose, double *joints, int *warnings);
typedef int (*kingen_forward_fn)(const void *geometry, const double *joints, int posture, const double *seed,
                                 double *pose, int *iterations);
typedef int (*kingen_machine_pose_fn)(const double *pose, double *machine);

void kingen_c_inverse_batch(void *function, const void *geometry, int count, const double *poses, double *joints,
                            int joint_stride, int *warnings, int warning_stride, int *returns)
{
    kingen_inverse_fn inverse = (kingen_inverse_fn)function;
    int n;
    for (n = 0; n < count; n++)
        returns[n] = inverse(geometry, poses + 16 * n, joints + joint_stride * n, warnings + warning_stride * n);
}

void kingen_c_forward_batch(void *function, const void *geometry, int count, const double *joints, int dof,
                            const int *postures, const double *seeds, double *poses, int *iterations, int *returns)
{
    kingen_forward_fn forward = (kingen_forward_fn)function;
    int n;
    for (n = 0; n < count; n++)
        returns[n] = forward(geometry, joints + dof * n, postures[n], seeds + 16 * n, poses + 16 * n, iterations + n);
}

/* A machine with task coordinates: its machine pose of each pose, returns[n] the status. */
void kingen_c_machine_pose_batch(void *function, int count, const double *poses, double *machines, int *returns)
{
    kingen_machine_pose_fn machine_pose = (kingen_machine_pose_fn)function;
    int n;
    for (n = 0; n < count; n++)
        returns[n] = machine_pose(poses + 16 * n, machines + 16 * n);
}

/* calls calls of the inverse over the pool of pool_count poses (taken in turn), the
 * nanoseconds of each in ns[]: clock_gettime before and after every call. */
void kingen_c_timed_batch(void *function, const void *geometry, int calls, int pool_count, const double *poses,
                          double *joints, int *warnings, double *ns)
{
    kingen_inverse_fn inverse = (kingen_inverse_fn)function;
    struct timespec before, after;
    int n;
    for (n = 0; n < calls; n++) {
        clock_gettime(CLOCK_MONOTONIC, &before);
        inverse(geometry, poses + 16 * (n % pool_count), joints, warnings);
        clock_gettime(CLOCK_MONOTONIC, &after);
        ns[n] = (double)(after.tv_sec - before.tv_sec) * 1e9 + (double)(after.tv_nsec - before.tv_nsec);
    }
}
