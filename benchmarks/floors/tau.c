/* Floor for robots/tau.yaml: three carriages on rails along -z, each driving one link of
 * length l: with w = R n + p - s - d, q = u.w -/+ sqrt(l^2 - |w|^2 + (u.w)^2) - origin (mm),
 * branch 0 the minus sign; carriage k is posture digit 2 - k. Calibrated: l from
 * link_lengths[k], origin from link_offsets[k]. Travel [-1, 2600] mm. */
#include "floor.h"

#define DOF 3
#define POSTURES 8
#define LOWER (-1.0)
#define UPPER 2600.0

/* s + d (mm, base frame), n (mm, platform frame), l (mm); u = (0, 0, -1) for all three. */
static const double foot[DOF][3] = {
    { -96.569, -185.0, -400.0 }, { -1100.0, 377.157, -173.726 }, { -2103.431, 0.0, -400.0 }
};
static const double platform[DOF][3] = {
    { 224.999, -240.001, 171.568 }, { 0.0, 39.705, 336.862 }, { -182.574, -80.0, 213.994 }
};
static const double link[DOF] = { 1500.0, 1500.0, 1499.775 };

DllExport int get_kin_config(char *kin_routine, int *kin_dof, int *solution_count, int *usrKinDataHint)
{
    if (kin_routine == NULL || strcmp(kin_routine, "kin_tau") != 0)
        return 1;
    *kin_dof = DOF;
    *solution_count = POSTURES;
    *usrKinDataHint = USR_KIN_DATA_NULL;
    return 0;
}

DllExport int kin_tau(double link_lengths[], double link_offsets[], double T6[4][4],
                      double solutions[][POSTURES], int warnings[], void *pData)
{
    double value[DOF][2];
    int severity[DOF][2], i, k, reachable = 0;
    (void)pData;
    if (!kin_check_definition(DOF, POSTURES))
        return 1;
    for (i = 0; i < DOF; i++) {
        const double *n = platform[i];
        double l = floor_field(link_lengths, i, 1.0, link[i]);
        double origin = floor_field(link_offsets, i, 1.0, 0.0);
        double w0 = T6[0][0] * n[0] + T6[1][0] * n[1] + T6[2][0] * n[2] + T6[3][0] - foot[i][0];
        double w1 = T6[0][1] * n[0] + T6[1][1] * n[1] + T6[2][1] * n[2] + T6[3][1] - foot[i][1];
        double w2 = T6[0][2] * n[0] + T6[1][2] * n[1] + T6[2][2] * n[2] + T6[3][2] - foot[i][2];
        double along = -w2, radicand = l * l - w0 * w0 - w1 * w1;
        double root = radicand > 0.0 ? sqrt(radicand) : 0.0;
        int status = floor_classify(radicand / (l * l));
        int branch;
        value[i][0] = along - root - origin;
        value[i][1] = along + root - origin;
        if (!FLOOR_FINITE(value[i][0]) || !FLOOR_FINITE(value[i][1])) {
            value[i][0] = value[i][1] = 0.0;
            status = FLOOR_UNREACHABLE;
        }
        for (branch = 0; branch < 2; branch++)
            severity[i][branch] = (status == FLOOR_OK && (value[i][branch] < LOWER || value[i][branch] > UPPER))
                                  ? FLOOR_LIMITS : status;
    }
    for (k = 0; k < POSTURES; k++) {
        int b0 = (k >> 2) & 1, b1 = (k >> 1) & 1, b2 = k & 1, worst = severity[0][b0];
        solutions[0][k] = value[0][b0];
        solutions[1][k] = value[1][b1];
        solutions[2][k] = value[2][b2];
        if (severity[1][b1] > worst)
            worst = severity[1][b1];
        if (severity[2][b2] > worst)
            worst = severity[2][b2];
        warnings[k] = floor_warning[worst];
        reachable |= worst != FLOOR_UNREACHABLE;
    }
    return reachable ? 0 : 1;
}
