/* abi_client.c: loads a user-kinematics library through the plain C ABI, as DELMIA does,
 * without kingen: this executable itself provides the host symbols (link with -rdynamic).
 *
 * usage: abi_client LIBRARY ROUTINE < lines of 16 numbers (T6 row by row)
 * prints: "config DOF SOLUTIONS HINT", then per line "RETURN W0..Wk-1 Q[0][0] Q[0][1] ..."
 * (joint-major: all postures of joint 0, then of joint 1, ...).
 */
#include <dlfcn.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>

typedef int (*config_function)(char *, int *, int *, int *);
typedef int (*routine_function)(double *, double *, double (*)[4], double *, int *, void *);

static int device_dof, device_solutions;

int DNBVMAP_kin_check_definition(int dof, int solutions)
{
    return dof == device_dof && solutions == device_solutions;
}
double DNBVMAP_Sqrt(double x) { return sqrt(x); }
double DNBVMAP_Asin(double x) { return asin(x); }
double DNBVMAP_Acos(double x) { return acos(x); }
double DNBVMAP_Atan(double x) { return atan(x); }
double DNBVMAP_Atan2(double y, double x) { return atan2(y, x); }

int main(int argc, char **argv)
{
    void *library;
    config_function config;
    routine_function routine;
    int hint, i, status;
    double t6[4][4], lengths[6] = {0}, offsets[6] = {0}, *solutions;
    int *warnings;

    if (argc != 3) {
        fprintf(stderr, "usage: abi_client LIBRARY ROUTINE\n");
        return 2;
    }
    library = dlopen(argv[1], RTLD_NOW);
    if (library == NULL) {
        fprintf(stderr, "%s\n", dlerror());
        return 2;
    }
    *(void **)&config = dlsym(library, "get_kin_config");
    *(void **)&routine = dlsym(library, argv[2]);
    if (config == NULL || routine == NULL || config(argv[2], &device_dof, &device_solutions, &hint) != 0) {
        fprintf(stderr, "routine %s not offered\n", argv[2]);
        return 2;
    }
    printf("config %d %d %d\n", device_dof, device_solutions, hint);
    solutions = malloc(sizeof(double) * device_dof * device_solutions);
    warnings = malloc(sizeof(int) * device_solutions);
    for (;;) {
        for (i = 0; i < 16; i++)
            if (scanf("%lf", &t6[i / 4][i % 4]) != 1)
                return 0;
        status = routine(lengths, offsets, t6, solutions, warnings, NULL);
        printf("%d", status);
        for (i = 0; i < device_solutions; i++)
            printf(" %d", warnings[i]);
        for (i = 0; i < device_dof * device_solutions; i++)
            printf(" %.17g", solutions[i]);
        printf("\n");
    }
}
