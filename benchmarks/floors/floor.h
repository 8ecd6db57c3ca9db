/* floor.h: what the hand-written floor routines share. Each floor is what a careful
 * engineer would write by hand for one robot, honouring the contract kingen's generated
 * routines honour (docs/explanation/delmia-abi.md, docs/explanation/conventions.md): host math and
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
/* Unroll the loop over the limbs, so each limb's table row folds into constants. */
#if defined(__GNUC__) && !defined(__clang__) && !defined(__TINYC__)
#define FLOOR_UNROLL _Pragma("GCC unroll 8")
#else
#define FLOOR_UNROLL
#endif

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

/* margin = a value positive exactly when M - d^2 diag(0, 0, 0, 1, 1, 1) is positive definite
 * (the direct index lies above d), M given entry by entry as ENTRY(n) (packed lower triangle,
 * row by row) with force block A, moment rows of the mixed block B and moment block C: A's
 * leading minors and those of X = det(A) (C - d^2 I) - B adj(A) B^T positive (Sylvester,
 * Schur complement), margin their least. No division and no branch, so a loop over
 * postures around it vectorises; a macro, so ENTRY may index the caller's partial sums. */
#define FLOOR_DIRECT_MARGIN(ENTRY, d, margin)                                                          \
    {                                                                                                  \
        const double a00 = ENTRY(0), a10 = ENTRY(1), a11 = ENTRY(2), a20 = ENTRY(3), a21 = ENTRY(4);   \
        const double a22 = ENTRY(5), b00 = ENTRY(6), b01 = ENTRY(7), b02 = ENTRY(8), c00 = ENTRY(9);   \
        const double b10 = ENTRY(10), b11 = ENTRY(11), b12 = ENTRY(12), c10 = ENTRY(13);               \
        const double c11 = ENTRY(14), b20 = ENTRY(15), b21 = ENTRY(16), b22 = ENTRY(17);               \
        const double c20 = ENTRY(18), c21 = ENTRY(19), c22 = ENTRY(20);                                \
        const double adj00 = a11 * a22 - a21 * a21, adj11 = a00 * a22 - a20 * a20;                    \
        const double adj22 = a00 * a11 - a10 * a10, adj10 = a20 * a21 - a10 * a22;                    \
        const double adj20 = a10 * a21 - a11 * a20, adj21 = a10 * a20 - a00 * a21;                    \
        const double det = a00 * adj00 + a10 * adj10 + a20 * adj20, shift = det * (d) * (d);           \
        const double q00 = b00 * adj00 + b01 * adj10 + b02 * adj20;                                    \
        const double q01 = b00 * adj10 + b01 * adj11 + b02 * adj21;                                    \
        const double q02 = b00 * adj20 + b01 * adj21 + b02 * adj22;                                    \
        const double q10 = b10 * adj00 + b11 * adj10 + b12 * adj20;                                    \
        const double q11 = b10 * adj10 + b11 * adj11 + b12 * adj21;                                    \
        const double q12 = b10 * adj20 + b11 * adj21 + b12 * adj22;                                    \
        const double q20 = b20 * adj00 + b21 * adj10 + b22 * adj20;                                    \
        const double q21 = b20 * adj10 + b21 * adj11 + b22 * adj21;                                    \
        const double q22 = b20 * adj20 + b21 * adj21 + b22 * adj22;                                    \
        const double x00 = det * c00 - shift - (q00 * b00 + q01 * b01 + q02 * b02);                    \
        const double x10 = det * c10 - (q10 * b00 + q11 * b01 + q12 * b02);                            \
        const double x11 = det * c11 - shift - (q10 * b10 + q11 * b11 + q12 * b12);                    \
        const double x20 = det * c20 - (q20 * b00 + q21 * b01 + q22 * b02);                            \
        const double x21 = det * c21 - (q20 * b10 + q21 * b11 + q22 * b12);                            \
        const double x22 = det * c22 - shift - (q20 * b20 + q21 * b21 + q22 * b22);                    \
        const double minor2 = x00 * x11 - x10 * x10;                                                   \
        const double minor3 = x00 * (x11 * x22 - x21 * x21) - x10 * (x10 * x22 - x21 * x20)            \
                              + x20 * (x10 * x21 - x11 * x20);                                         \
        double least = a00 < adj22 ? a00 : adj22;                                                      \
        least = least < det ? least : det;                                                             \
        least = least < x00 ? least : x00;                                                             \
        least = least < minor2 ? least : minor2;                                                       \
        (margin) = least < minor3 ? least : minor3; /* NaN anywhere in M: minor3, so margin, NaN */    \
    }

#endif
