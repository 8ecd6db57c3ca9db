/* floor.h: what the hand-written floor routines share. Each floor is what a careful
 * engineer would write by hand for one robot, honouring the contract kingen's generated
 * routines honour (docs/delmia-abi.md, docs/conventions.md): host math and
 * kin_check_definition through the header, the robot's calibration fields, the singular
 * band, WARN_* precedence, travel limits, finite joints for NaN, inf and overflowing T6,
 * and the direct index where the robot file asks for it. They exist to measure how far the
 * generated code is from the floor (benchmarks/run.py); `kingen verify --source` passes them.
 */
#ifndef FLOOR_H
#define FLOOR_H

#include "shlibdefs.h"

#define FLOOR_SINGULAR_TOL 1e-5
#define FLOOR_PI 3.14159265358979323846
#define FLOOR_FINITE(x) ((x) - (x) == 0.0)

/* Severities, worst last: the warning of each. */
enum { FLOOR_OK, FLOOR_LIMITS, FLOOR_SINGULAR, FLOOR_UNREACHABLE };
static const int floor_warning[4] = {
    WARN_GOOD_SOLUTION, WARN_JOINT_LIMITS_EXCEEDED, WARN_SINGULAR_SOLUTION, WARN_UNREACHABLE
};

static int floor_classify(double radicand)
{
    if (!(radicand >= -FLOOR_SINGULAR_TOL))
        return FLOOR_UNREACHABLE;
    return radicand <= FLOOR_SINGULAR_TOL ? FLOOR_SINGULAR : FLOOR_OK;
}

/* get_kin_config answering routine `name` with `dof` joints and `postures` solutions. */
#define FLOOR_KIN_CONFIG(name, dof, postures)                                                       \
    DllExport int get_kin_config(char *kin_routine, int *kin_dof, int *solution_count, int *usrKinDataHint) \
    {                                                                                               \
        if (kin_routine == NULL || strcmp(kin_routine, name) != 0)                                  \
            return 1;                                                                               \
        *kin_dof = dof;                                                                             \
        *solution_count = postures;                                                                 \
        *usrKinDataHint = USR_KIN_DATA_NULL;                                                        \
        return 0;                                                                                   \
    }

/* c = R t + p - origin (mm, base frame) from the transposed T6. */
static void floor_point(double T6[4][4], const double t[3], const double origin[3], double c[3])
{
    c[0] = T6[0][0] * t[0] + T6[1][0] * t[1] + T6[2][0] * t[2] + T6[3][0] - origin[0];
    c[1] = T6[0][1] * t[0] + T6[1][1] * t[1] + T6[2][1] * t[2] + T6[3][1] - origin[1];
    c[2] = T6[0][2] * t[0] + T6[1][2] * t[1] + T6[2][2] * t[2] + T6[3][2] - origin[2];
}

/* A dialog value (0 or non-finite: keep the built-in one) times scale. */
static double floor_field(const double *values, int index, double scale, double built_in)
{
    double value;
    if (values == NULL)
        return built_in;
    value = values[index];
    return (value != 0.0 && FLOOR_FINITE(value)) ? value * scale : built_in;
}

/* An angle in (-pi, pi]: one 2 pi step, fmod only for angles further out. */
static double floor_wrap(double angle)
{
    if (angle > FLOOR_PI)
        angle -= 2.0 * FLOOR_PI;
    else if (angle <= -FLOOR_PI)
        angle += 2.0 * FLOOR_PI;
    if (angle > -FLOOR_PI && angle <= FLOOR_PI)
        return angle;
    angle = fmod(angle + FLOOR_PI, 2.0 * FLOOR_PI);
    if (angle < 0.0)
        angle += 2.0 * FLOOR_PI;
    angle -= FLOOR_PI;
    return angle == -FLOOR_PI ? FLOOR_PI : angle;
}

/* m += w w^T (packed lower triangle, row by row) for the line through c along unit f:
 * w = [f; c x f]. */
static void floor_add_line(double m[21], const double c[3], const double f[3])
{
    const double w0 = f[0], w1 = f[1], w2 = f[2];
    const double w3 = c[1] * f[2] - c[2] * f[1], w4 = c[2] * f[0] - c[0] * f[2], w5 = c[0] * f[1] - c[1] * f[0];
    m[0] += w0 * w0;
    m[1] += w1 * w0; m[2] += w1 * w1;
    m[3] += w2 * w0; m[4] += w2 * w1; m[5] += w2 * w2;
    m[6] += w3 * w0; m[7] += w3 * w1; m[8] += w3 * w2; m[9] += w3 * w3;
    m[10] += w4 * w0; m[11] += w4 * w1; m[12] += w4 * w2; m[13] += w4 * w3; m[14] += w4 * w4;
    m[15] += w5 * w0; m[16] += w5 * w1; m[17] += w5 * w2; m[18] += w5 * w3; m[19] += w5 * w4; m[20] += w5 * w5;
}

/* 1 when M - d^2 diag(0, 0, 0, 1, 1, 1) is not positive definite: the direct index is at
 * most d. LDL^T written out (u = l p), stopping at the first pivot p <= 0. */
static int floor_direct_singular(const double m[21], double d)
{
    double p0, p1, p2, p3, p4, p5, r0, r1, r2, r3, r4;
    double u10, u20, u30, u40, u50, u21, u31, u41, u51, u32, u42, u52, u43, u53, u54;
    double l10, l20, l30, l40, l50, l21, l31, l41, l51, l32, l42, l52, l43, l53, l54;
    p0 = m[0];
    if (!(p0 > 0.0))
        return 1;
    r0 = 1.0 / p0;
    u10 = m[1];
    l10 = u10 * r0;
    u20 = m[3];
    l20 = u20 * r0;
    u30 = m[6];
    l30 = u30 * r0;
    u40 = m[10];
    l40 = u40 * r0;
    u50 = m[15];
    l50 = u50 * r0;
    p1 = m[2] - u10 * l10;
    if (!(p1 > 0.0))
        return 1;
    r1 = 1.0 / p1;
    u21 = m[4] - u20 * l10;
    l21 = u21 * r1;
    u31 = m[7] - u30 * l10;
    l31 = u31 * r1;
    u41 = m[11] - u40 * l10;
    l41 = u41 * r1;
    u51 = m[16] - u50 * l10;
    l51 = u51 * r1;
    p2 = m[5] - u20 * l20 - u21 * l21;
    if (!(p2 > 0.0))
        return 1;
    r2 = 1.0 / p2;
    u32 = m[8] - u30 * l20 - u31 * l21;
    l32 = u32 * r2;
    u42 = m[12] - u40 * l20 - u41 * l21;
    l42 = u42 * r2;
    u52 = m[17] - u50 * l20 - u51 * l21;
    l52 = u52 * r2;
    p3 = m[9] - d * d - u30 * l30 - u31 * l31 - u32 * l32;
    if (!(p3 > 0.0))
        return 1;
    r3 = 1.0 / p3;
    u43 = m[13] - u40 * l30 - u41 * l31 - u42 * l32;
    l43 = u43 * r3;
    u53 = m[18] - u50 * l30 - u51 * l31 - u52 * l32;
    l53 = u53 * r3;
    p4 = m[14] - d * d - u40 * l40 - u41 * l41 - u42 * l42 - u43 * l43;
    if (!(p4 > 0.0))
        return 1;
    r4 = 1.0 / p4;
    u54 = m[19] - u50 * l40 - u51 * l41 - u52 * l42 - u53 * l43;
    l54 = u54 * r4;
    p5 = m[20] - d * d - u50 * l50 - u51 * l51 - u52 * l52 - u53 * l53 - u54 * l54;
    return !(p5 > 0.0);
}

#endif
