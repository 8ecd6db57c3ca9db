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

FLOOR_KIN_CONFIG("kin_tau", DOF, POSTURES)

DllExport int kin_tau(double link_lengths[], double link_offsets[], double T6[4][4],
                      double solutions[][POSTURES], int warnings[], void *pData)
{
    double value[DOF][2];
    int severity[DOF][2], i, k, reachable = 0;
    (void)pData;
    if (!kin_check_definition(DOF, POSTURES))
        return 1;
    FLOOR_UNROLL
    for (i = 0; i < DOF; i++) {
        double l = floor_field(link_lengths, i, 1.0, link[i]);
        double origin = floor_field(link_offsets, i, 1.0, 0.0);
        double w[3], along, radicand, root;
        int status, branch;
        floor_point(T6, platform[i], foot[i], w);
        along = -w[2];
        radicand = l * l - w[0] * w[0] - w[1] * w[1];
        root = radicand > 0.0 ? sqrt(radicand) : 0.0;
        status = floor_classify(radicand / (l * l));
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
