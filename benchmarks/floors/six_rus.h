/* six_rus.h: the floor routine of a six-crank (6-RUS) robot, 64 postures, no travel limits,
 * with a direct-index threshold; the robot's file (ceart.c, iwf.c, rus_optimized.c) defines
 * its geometry and includes this. Crank tip B = A + r (cos t cos b, cos t sin b, -sin t);
 * t = phi +/- acos(K / rho) - zero (radians), branch 0 the plus sign, crank k is posture
 * digit 5 - k; zero from link_offsets[k] in degrees when ZERO_FROM_OFFSETS, else 0. Every
 * posture has the same limb severity; a direct index at most DIRECT_MIN mm is singular.
 *
 * The includer defines ROUTINE (the function), ROUTINE_NAME (its name as a string), CRANK
 * and ROD (r and L, mm), DIRECT_MIN (mm), ZERO_FROM_OFFSETS (0 or 1), and the tables
 * pivot[6][3] (A, mm, base frame), direction[6][2] (cos b, sin b) and platform[6][3] (c, mm,
 * platform frame): the values kingen's rus6 layout computes from the robot file. */
#ifndef SIX_RUS_H
#define SIX_RUS_H

#include "floor.h"

#define DOF 6
#define POSTURES 64

FLOOR_KIN_CONFIG(ROUTINE_NAME, DOF, POSTURES)

static const double floor_origin[3] = { 0.0, 0.0, 0.0 };

DllExport int ROUTINE(double link_lengths[], double link_offsets[], double T6[4][4],
                      double solutions[][POSTURES], int warnings[], void *pData)
{
    double value[DOF][2], line[DOF][2][21], high[21][8], low[21][8], margin[POSTURES];
    int i, k, branch, worst = FLOOR_OK;
    (void)link_lengths; (void)pData;
    if (!kin_check_definition(DOF, POSTURES))
        return 1;
    FLOOR_UNROLL
    for (i = 0; i < DOF; i++) {
        const double cb = direction[i][0], sb = direction[i][1];
        double c[3], g[3], a, b, kk, rho2, radicand, cosine, half, phi, zero;
        int status;
        floor_point(T6, platform[i], floor_origin, c);
        g[0] = c[0] - pivot[i][0];
        g[1] = c[1] - pivot[i][1];
        g[2] = c[2] - pivot[i][2];
        a = g[0] * cb + g[1] * sb;
        b = -g[2];
        kk = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2] + CRANK * CRANK - ROD * ROD) / (2.0 * CRANK);
        rho2 = a * a + b * b;
        radicand = -1.0;
        cosine = 1.0;
        if (rho2 > 0.0) {
            radicand = (rho2 - kk * kk) / rho2;
            cosine = kk / sqrt(rho2);
        }
        cosine = cosine > 1.0 ? 1.0 : cosine < -1.0 ? -1.0 : cosine;
        half = acos(cosine);
        phi = atan2(b, a);
        zero = ZERO_FROM_OFFSETS ? floor_field(link_offsets, i, FLOOR_PI / 180.0, 0.0) : 0.0;
        value[i][0] = floor_wrap(phi + half - zero);
        value[i][1] = floor_wrap(phi - half - zero);
        status = floor_classify(radicand);
        if (!FLOOR_FINITE(value[i][0]) || !FLOOR_FINITE(value[i][1])) {
            value[i][0] = value[i][1] = 0.0;
            status = FLOOR_UNREACHABLE;
        }
        if (status > worst)
            worst = status;
        if (worst < FLOOR_SINGULAR) {
            double rho = sqrt(rho2), sin_half = sqrt(radicand);
            double per_rho = 1.0 / rho, cp = a * per_rho, sp = b * per_rho;
            double ct[2], st[2];
            ct[0] = cp * cosine - sp * sin_half;
            st[0] = sp * cosine + cp * sin_half;
            ct[1] = cp * cosine + sp * sin_half;
            st[1] = sp * cosine - cp * sin_half;
            for (branch = 0; branch < 2; branch++) {
                double f[3];
                int n;
                f[0] = (g[0] - CRANK * ct[branch] * cb) * (1.0 / ROD);
                f[1] = (g[1] - CRANK * ct[branch] * sb) * (1.0 / ROD);
                f[2] = (g[2] + CRANK * st[branch]) * (1.0 / ROD);
                for (n = 0; n < 21; n++)
                    line[i][branch][n] = 0.0;
                floor_add_line(line[i][branch], c, f);
            }
        }
    }
    for (i = 0; i < DOF; i++) { /* crank i takes branch 0 in blocks of 2^(5 - i) postures, then branch 1 */
        const int block = 1 << (5 - i);
        int j;
        for (k = 0; k < POSTURES; k += 2 * block)
            for (j = 0; j < block; j++) {
                solutions[i][k + j] = value[i][0];
                solutions[i][k + block + j] = value[i][1];
            }
    }
    if (worst >= FLOOR_SINGULAR) {
        for (k = 0; k < POSTURES; k++)
            warnings[k] = floor_warning[worst];
        return worst == FLOOR_UNREACHABLE;
    }
    /* A posture's M: the sum over cranks 0-2 (digits 5-3) plus the sum over cranks 3-5, kept
     * entry by entry so that the loop over the low digits below runs along memory; each sum
     * of three lines from the four sums of the first two. */
    for (k = 0; k < 21; k++) {
        int triple;
        for (triple = 0; triple < 2; triple++) {
            double (*first)[21] = line[3 * triple], (*second)[21] = line[3 * triple + 1];
            double (*third)[21] = line[3 * triple + 2];
            double *sum = triple == 0 ? high[k] : low[k];
            const double s00 = first[0][k] + second[0][k], s01 = first[0][k] + second[1][k];
            const double s10 = first[1][k] + second[0][k], s11 = first[1][k] + second[1][k];
            sum[0] = s00 + third[0][k];
            sum[1] = s00 + third[1][k];
            sum[2] = s01 + third[0][k];
            sum[3] = s01 + third[1][k];
            sum[4] = s10 + third[0][k];
            sum[5] = s10 + third[1][k];
            sum[6] = s11 + third[0][k];
            sum[7] = s11 + third[1][k];
        }
    }
#define POSTURE_ENTRY(n) (high[n][k >> 3] + low[n][j])
    for (k = 0; k < POSTURES; k += 8) {
        int j;
        for (j = 0; j < 8; j++)
            FLOOR_DIRECT_MARGIN(POSTURE_ENTRY, DIRECT_MIN, margin[k + j])
    }
    for (k = 0; k < POSTURES; k++)
        warnings[k] = margin[k] > 0.0 ? WARN_GOOD_SOLUTION : WARN_SINGULAR_SOLUTION;
    return 0;
}

#endif
