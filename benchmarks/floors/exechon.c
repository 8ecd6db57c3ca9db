/* Floor for robots/exechon.yaml: three legs, q = |R t + p - b| - L0 (mm), one posture,
 * L0 calibrated from link_lengths[0..2], travel limits per leg, no direct index (3 legs). */
#include "floor.h"

#define DOF 3

static const double base[DOF][3] = { { 420.0, 0.0, 0.0 }, { -420.0, 0.0, 0.0 }, { 0.0, 670.0, 0.0 } };
static const double platform[DOF][3] = { { 173.0, -50.0, 485.0 }, { -173.0, -50.0, 485.0 }, { 0.0, 173.0, 485.0 } };
static const double reference_length[DOF] = { 803.887, 803.887, 886.021 };
static const double lower[DOF] = { -150.0, -150.0, -225.0 };
static const double upper[DOF] = { 595.0, 595.0, 520.0 };

FLOOR_KIN_CONFIG("kin_exechon", DOF, 1)

DllExport int kin_exechon(double link_lengths[], double link_offsets[], double T6[4][4],
                          double solutions[][1], int warnings[], void *pData)
{
    int i, worst = FLOOR_OK;
    (void)link_offsets; (void)pData;
    if (!kin_check_definition(DOF, 1))
        return 1;
    FLOOR_UNROLL
    for (i = 0; i < DOF; i++) {
        double d[3], q;
        floor_point(T6, platform[i], base[i], d);
        q = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - floor_field(link_lengths, i, 1.0, reference_length[i]);
        if (!FLOOR_FINITE(q)) {
            q = 0.0;
            worst = FLOOR_UNREACHABLE;
        } else if ((q < lower[i] || q > upper[i]) && worst < FLOOR_LIMITS) {
            worst = FLOOR_LIMITS;
        }
        solutions[i][0] = q;
    }
    warnings[0] = floor_warning[worst];
    return worst == FLOOR_UNREACHABLE;
}
