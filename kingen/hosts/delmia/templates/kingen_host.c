/* kingen_host.c: the part of DELMIA V5 / IGRIP a user-kinematics plugin links against.
 *
 * Provides the host symbols the vendor header maps to (DNBVMAP_kin_check_definition
 * and the DNBVMAP_* math functions), records how kin_check_definition was called,
 * can be told to refuse, and drives a routine over an array of T6 in one call:
 * kingen_host_run_batch as fast as possible (for benchmarks), kingen_host_run_guarded
 * with every output buffer placed between inaccessible zones of 1 MiB, so that a write past
 * (or far before) solutions[][] or warnings[] faults at once and is named, not silently
 * corrupting memory. Loaded with global symbol visibility before any plugin, as the
 * host process is.
 */
#define _DEFAULT_SOURCE 1
#define KINGEN_HOST 1
#include "shlibdefs.h"
#ifndef _WIN32
#include <setjmp.h>
#include <signal.h>
#include <sys/mman.h>
#include <stdlib.h>
#include <unistd.h>
#endif

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

/* Each limb's value in its two branches, read at the postures first_postures (dof x 2) names,
 * into branch_values (dof x 2); returns 1 when every posture's value of every limb equals (==:
 * NaN never does) the value of the branch it takes, branch_of (postures x dof), else 0. */
int kingen_host_summarise_branches(const double *solution, int dof, int postures, const int *first_postures,
                                   const int *branch_of, double *branch_values)
{
    int limb, posture, repeats = 1;
    for (limb = 0; limb < dof; limb++) {
        const double *values = solution + (size_t)limb * postures;
        double *branches = branch_values + 2 * limb;
        branches[0] = values[first_postures[2 * limb]];
        branches[1] = values[first_postures[2 * limb + 1]];
        for (posture = 0; posture < postures; posture++)
            repeats &= values[posture] == branches[branch_of[posture * dof + limb]];
    }
    return repeats;
}

#ifndef _WIN32
/* KINGEN_WROTE_* (fault bits per pose) and KINGEN_UNWRITTEN_WARNING come from kingen/abi.py
 * through the stand-in header. */
#define KINGEN_GUARD_DOUBLE (-7.0e300)
#define KINGEN_GUARD_INT (-20260001)
#define KINGEN_PAD_ENTRIES 64
#define KINGEN_GUARD_BYTES ((size_t)1 << 20) /* inaccessible on each side: 131072 doubles */

typedef struct {
    char *base;           /* mapping: guard zone, pad + data, guard zone */
    size_t size;
    char *data;           /* first byte of the buffer handed to the routine */
    size_t data_bytes;
    char *pad;            /* sentinel-filled bytes between the leading guard zone and data */
    char *after;          /* the trailing guard zone, right after the last data byte */
    char *reference;      /* what the pad holds when intact */
} kingen_guarded;

static sigjmp_buf guard_jump;
static volatile sig_atomic_t guard_armed = 0;
static volatile int guard_fault = 0;
static kingen_guarded *guard_regions[2];
static struct sigaction previous_segv, previous_bus;

static void fill_pad(kingen_guarded *region, int doubles);

static int guarded_open(kingen_guarded *region, size_t data_bytes, int doubles)
{
    size_t page = (size_t)sysconf(_SC_PAGESIZE);
    size_t body = ((data_bytes + KINGEN_PAD_ENTRIES * sizeof(double) + page - 1) / page) * page;
    void *base = mmap(NULL, body + 2 * KINGEN_GUARD_BYTES, PROT_READ | PROT_WRITE, MAP_PRIVATE | MAP_ANONYMOUS,
                      -1, 0);
    if (base == MAP_FAILED)
        return 0;
    region->base = (char *)base;
    region->size = body + 2 * KINGEN_GUARD_BYTES;
    region->after = region->base + KINGEN_GUARD_BYTES + body;
    region->data = region->after - data_bytes;
    region->data_bytes = data_bytes;
    region->pad = region->base + KINGEN_GUARD_BYTES;
    if (mprotect(region->base, KINGEN_GUARD_BYTES, PROT_NONE) != 0
        || mprotect(region->after, KINGEN_GUARD_BYTES, PROT_NONE) != 0) {
        munmap(base, region->size);
        region->base = NULL;
        return 0;
    }
    fill_pad(region, doubles);
    region->reference = (char *)malloc((size_t)(region->data - region->pad) + 1);
    if (region->reference == NULL) {
        munmap(base, region->size);
        region->base = NULL;
        return 0;
    }
    memcpy(region->reference, region->pad, (size_t)(region->data - region->pad));
    return 1;
}

static void guarded_close(kingen_guarded *region)
{
    if (region->base != NULL)
        munmap(region->base, region->size);
    free(region->reference);
    region->base = NULL;
    region->reference = NULL;
}

static void on_fault(int signal_number, siginfo_t *info, void *context)
{
    char *address = (char *)info->si_addr;
    int i;
    (void)context;
    if (guard_armed)
        for (i = 0; i < 2; i++) {
            kingen_guarded *region = guard_regions[i];
            if (address >= region->base && address < region->base + KINGEN_GUARD_BYTES) {
                guard_fault = i == 0 ? KINGEN_WROTE_BEFORE_SOLUTIONS : KINGEN_WROTE_BEFORE_WARNINGS;
                siglongjmp(guard_jump, 1);
            }
            if (address >= region->after && address < region->after + KINGEN_GUARD_BYTES) {
                guard_fault = i == 0 ? KINGEN_WROTE_AFTER_SOLUTIONS : KINGEN_WROTE_AFTER_WARNINGS;
                siglongjmp(guard_jump, 1);
            }
        }
    /* Not a guard zone: a real crash. Restore the default action and let it happen. */
    signal(signal_number, SIG_DFL);
}

static void fill_pad(kingen_guarded *region, int doubles)
{
    if (doubles) {
        double *value;
        for (value = (double *)region->pad; (char *)value < region->data; value++)
            *value = KINGEN_GUARD_DOUBLE;
    } else {
        int *value;
        for (value = (int *)region->pad; (char *)value < region->data; value++)
            *value = KINGEN_GUARD_INT;
    }
}

/* The pad still holds its sentinels (compared with the copy taken when it was filled);
 * if not, it is filled again for the next call. */
static int pad_intact(kingen_guarded *region, int doubles)
{
    size_t bytes = (size_t)(region->data - region->pad);
    if (memcmp(region->pad, region->reference, bytes) == 0)
        return 1;
    fill_pad(region, doubles);
    return 0;
}

/* Call the routine once per T6 with guarded buffers; outputs are copied to the caller's
 * contiguous arrays (solutions: count x dof x postures, warnings: count x postures).
 * Unwritten outputs keep the sentinels NaN and -1. faults[i] gets the KINGEN_WROTE_* bits
 * of pose i; after a fault the pose's outputs are what was written before it. With
 * first_postures and branch_of (else NULL), kingen_host_summarise_branches of each pose's solutions goes
 * to branch_values (count x dof x 2) and repeats[i]. Returns the number of poses with a
 * fault, or -1 when the guarded buffers cannot be set up. */
int kingen_host_run_guarded(void *routine, int count, double *t6, double *link_lengths, double *link_offsets,
                            int dof, int postures, double *solutions, int *warnings, int *returns,
                            int *faults, void *pData, const int *first_postures, const int *branch_of,
                            double *branch_values, int *repeats)
{
    kingen_routine call;
    kingen_guarded solution_region, warning_region;
    struct sigaction action;
    double inputs[28], copy[28], not_a_number;
    volatile double zero = 0.0;
    volatile int i, faulty = 0;
    size_t solution_bytes = (size_t)dof * (size_t)postures * sizeof(double);
    size_t warning_bytes = (size_t)postures * sizeof(int);
    int k;
    memcpy(&call, &routine, sizeof call);
    not_a_number = zero / zero;
    memset(&solution_region, 0, sizeof solution_region);
    memset(&warning_region, 0, sizeof warning_region);
    if (!guarded_open(&solution_region, solution_bytes, 1) || !guarded_open(&warning_region, warning_bytes, 0)) {
        guarded_close(&solution_region);
        return -1;
    }
    guard_regions[0] = &solution_region;
    guard_regions[1] = &warning_region;
    memset(&action, 0, sizeof action);
    action.sa_sigaction = on_fault;
    action.sa_flags = SA_SIGINFO | SA_NODEFER;
    sigemptyset(&action.sa_mask);
    sigaction(SIGSEGV, &action, &previous_segv);
    sigaction(SIGBUS, &action, &previous_bus);
    for (i = 0; i < count; i++) {
        double *solution_data = (double *)solution_region.data;
        int *warning_data = (int *)warning_region.data;
        memcpy(inputs, t6 + 16 * (size_t)i, 16 * sizeof(double));
        memcpy(inputs + 16, link_lengths, 6 * sizeof(double));
        memcpy(inputs + 22, link_offsets, 6 * sizeof(double));
        memcpy(copy, inputs, sizeof copy);
        for (k = 0; k < dof * postures; k++)
            solution_data[k] = not_a_number;
        for (k = 0; k < postures; k++)
            warning_data[k] = KINGEN_UNWRITTEN_WARNING;
        faults[i] = 0;
        returns[i] = -1;
        guard_fault = 0;
        if (sigsetjmp(guard_jump, 0) == 0) {
            guard_armed = 1;
            returns[i] = call(inputs + 16, inputs + 22, (double (*)[4])inputs, solution_data, warning_data, pData);
            guard_armed = 0;
        } else {
            guard_armed = 0;
            faults[i] = guard_fault;
        }
        if (!pad_intact(&solution_region, 1))
            faults[i] |= KINGEN_WROTE_BEFORE_SOLUTIONS;
        if (!pad_intact(&warning_region, 0))
            faults[i] |= KINGEN_WROTE_BEFORE_WARNINGS;
        if (memcmp(inputs, copy, sizeof copy) != 0)
            faults[i] |= KINGEN_WROTE_INPUTS;
        memcpy(solutions + (size_t)i * dof * postures, solution_data, solution_bytes);
        memcpy(warnings + (size_t)i * postures, warning_data, warning_bytes);
        if (first_postures != NULL)
            repeats[i] = kingen_host_summarise_branches(solution_data, dof, postures, first_postures, branch_of,
                                                        branch_values + (size_t)i * dof * 2);
        if (faults[i])
            faulty++;
    }
    sigaction(SIGSEGV, &previous_segv, NULL);
    sigaction(SIGBUS, &previous_bus, NULL);
    guarded_close(&solution_region);
    guarded_close(&warning_region);
    return faulty;
}
#else
int kingen_host_run_guarded(void *routine, int count, double *t6, double *link_lengths, double *link_offsets,
                            int dof, int postures, double *solutions, int *warnings, int *returns,
                            int *faults, void *pData, const int *first_postures, const int *branch_of,
                            double *branch_values, int *repeats)
{
    (void)first_postures; (void)branch_of; (void)branch_values; (void)repeats;
    (void)routine; (void)count; (void)t6; (void)link_lengths; (void)link_offsets; (void)dof; (void)postures;
    (void)solutions; (void)warnings; (void)returns; (void)faults; (void)pData;
    return -1;
}
#endif
