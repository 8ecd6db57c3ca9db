/* kingen's batch driver for C host libraries: the library's functions called from C over a
 * whole batch, through pointers, so that verify and bench measure the library, not Python. */
typedef int (*kingen_inverse_fn)(const void *geometry, const double *pose, double *joints, int *warnings);
typedef int (*kingen_forward_fn)(const void *geometry, const double *joints, int posture, const double *seed,
                                 double *pose, int *iterations);

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
