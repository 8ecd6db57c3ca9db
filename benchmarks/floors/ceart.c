/* Floor for robots/ceart.yaml: six RUS cranks, 64 postures. Crank tip
 * B = A + r (cos t cos b, cos t sin b, -sin t); t = phi +/- acos(K / rho) - zero (radians),
 * branch 0 the plus sign, crank k is posture digit 5 - k; zero from link_offsets[k] in
 * degrees. No travel limits, so every posture has the same limb severity; direct index at
 * most 29.3 mm is singular. */
#include "floor.h"

#define DOF 6
#define POSTURES 64
#define CRANK 194.0
#define ROD 650.0
#define DIRECT_MIN 29.3

/* A (mm, base frame), cos b, sin b, c (mm, platform frame): the values kingen's rus6
 * layout computes from the robot file. */
static const double pivot[DOF][3] = {
    { 636.885, 197.555, 0.0 }, { -147.3548513553651, 650.3360892892522, 0.0 },
    { -489.53014864463466, 452.7810892892523, 0.0 }, { -489.530148644635, -452.78108928925195, 0.0 },
    { -147.35485135536555, -650.3360892892522, 0.0 }, { 636.885, -197.555, 0.0 }
};
static const double direction[DOF][2] = {
    { -0.4999999999999998, 0.8660254037844387 }, { -1.0, 1.2246467991473532e-16 },
    { -0.5000000000000004, -0.8660254037844384 }, { 0.5000000000000001, -0.8660254037844386 },
    { 1.0, 0.0 }, { 0.5000000000000001, 0.8660254037844386 }
};
static const double platform[DOF][3] = {
    { 291.73, 402.345, 0.0 }, { 202.57599108565006, 453.8180910460343, 0.0 },
    { -494.30599108564996, 51.4730910460344, 0.0 }, { -494.30599108565, -51.47309104603403, 0.0 },
    { 202.57599108564975, -453.8180910460344, 0.0 }, { 291.73, -402.345, 0.0 }
};

FLOOR_KIN_CONFIG("kin_ceart", DOF, POSTURES)

static const double floor_origin[3] = { 0.0, 0.0, 0.0 };

DllExport int kin_ceart(double link_lengths[], double link_offsets[], double T6[4][4],
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
        zero = floor_field(link_offsets, i, FLOOR_PI / 180.0, 0.0);
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
