/* kingen_host.c: the part of DELMIA V5 / IGRIP a user-kinematics plugin links against.
 *
 * Provides the host symbols the vendor header maps to (DNBVMAP_kin_check_definition
 * and the DNBVMAP_* math functions), records how kin_check_definition was called,
 * can be told to refuse, and drives a routine over an array of T6 in one call.
 * Loaded with global symbol visibility before any plugin, as the host process is.
 */
#define KINGEN_HOST 1
#include "shlibdefs.h"

typedef int (*kingen_routine)(double *, double *, double (*)[4], double *, int *, void *);

static int expected_dof = -1;
static int expected_solutions = -1;
static int refusing = 0;
static int check_calls = 0;
static int last_dof = -1;
static int last_solutions = -1;

void kingen_host_reset(int dof_count, int solution_count)
{
    expected_dof = dof_count;
    expected_solutions = solution_count;
    refusing = 0;
    check_calls = 0;
    last_dof = -1;
    last_solutions = -1;
}

void kingen_host_refuse(int refuse)
{
    refusing = refuse;
}

int kingen_host_check_calls(void)
{
    return check_calls;
}

int kingen_host_last_dof(void)
{
    return last_dof;
}

int kingen_host_last_solutions(void)
{
    return last_solutions;
}

void kingen_host_flush(void)
{
    fflush(NULL);
}

int DNBVMAP_kin_check_definition(int dof_count, int solution_count)
{
    check_calls++;
    last_dof = dof_count;
    last_solutions = solution_count;
    if (refusing)
        return 0;
    return dof_count == expected_dof && solution_count == expected_solutions;
}

double DNBVMAP_Sqrt(double x) { return sqrt(x); }
double DNBVMAP_Asin(double x) { return asin(x); }
double DNBVMAP_Acos(double x) { return acos(x); }
double DNBVMAP_Atan(double x) { return atan(x); }
double DNBVMAP_Atan2(double y, double x) { return atan2(y, x); }

int kingen_host_run_batch(void *routine, int count, double *t6, double *link_lengths,
                          double *link_offsets, double *solutions, int solution_block,
                          int *warnings, int warning_block, int *returns, void *pData)
{
    kingen_routine call;
    int i;
    memcpy(&call, &routine, sizeof call);
    for (i = 0; i < count; i++)
        returns[i] = call(link_lengths, link_offsets, (double (*)[4])(t6 + 16 * (size_t)i),
                          solutions + (size_t)i * solution_block,
                          warnings + (size_t)i * warning_block, pData);
    return count;
}
