/* six_legs.h: the floor routine of a six-leg (S-P-S) robot, q = |R t + p - b| - L0 (mm), one
 * posture, no calibration fields, no travel limits, with a direct-index threshold; the
 * robot's file (hexapod.c, flexapod.c) defines its geometry and includes this.
 *
 * The includer defines ROUTINE (the function), ROUTINE_NAME (its name as a string),
 * DIRECT_MIN (mm), REFERENCE_LENGTH (L0, mm) and the tables base[6][3] (b, mm, base frame) and
 * platform[6][3] (t, mm, platform frame). */
#ifndef SIX_LEGS_H
#define SIX_LEGS_H

#include "floor.h"

#define DOF 6
static const double floor_origin[3] = { 0.0, 0.0, 0.0 };

FLOOR_KIN_CONFIG(ROUTINE_NAME, DOF, 1)

DllExport int ROUTINE(double link_lengths[], double link_offsets[], double T6[4][4],
                      double solutions[][1], int warnings[], void *pData)
{
    double m[21] = { 0.0 };
    double margin;
    int i, finite = 1;
    (void)link_lengths; (void)link_offsets; (void)pData;
    if (!kin_check_definition(DOF, 1))
        return 1;
    FLOOR_UNROLL
    for (i = 0; i < DOF; i++) {
        double c[3], f[3], length, q;
        floor_point(T6, platform[i], floor_origin, c);
        f[0] = c[0] - base[i][0];
        f[1] = c[1] - base[i][1];
        f[2] = c[2] - base[i][2];
        length = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
        q = length - REFERENCE_LENGTH;
        if (!FLOOR_FINITE(q)) {
            finite = 0;
            q = 0.0;
        }
        solutions[i][0] = q;
        length = 1.0 / length;
        f[0] *= length; f[1] *= length; f[2] *= length;
        floor_add_line(m, c, f);
    }
    if (!finite) {
        for (i = 0; i < DOF; i++)
            solutions[i][0] = 0.0;
        warnings[0] = WARN_UNREACHABLE;
        return 1;
    }
#define GRAM_ENTRY(n) (m[n])
    FLOOR_DIRECT_MARGIN(GRAM_ENTRY, DIRECT_MIN, margin)
    warnings[0] = margin > 0.0 ? WARN_GOOD_SOLUTION : WARN_SINGULAR_SOLUTION;
    return 0;
}

#endif
