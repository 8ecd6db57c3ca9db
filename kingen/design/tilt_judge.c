/* kingen's tilt judge: the largest tilt of a six-crank (6-RUS) platform towards each azimuth,
 * for a design given at run time. It decides each pose as kingen/analysis.py's evaluate()
 * does (the numpy reference), for six cranks without travel limits:
 *   unreachable          a limb's normalised radicand D <= 1e-5 (no solution, or its own singularity)
 *   direct_singularity   the direct index at most the threshold (the largest of the robot's
 *                        direct_index_min, 5 % of its value at home and analysis.SINGULAR of the
 *                        robot's size), or det W's sign not home's
 *   collision            rods (and cranks) closer than their radii, in the chosen model
 * (the first that holds, in this order). Lengths mm, angles radians, base frame. */
#include <math.h>

#ifndef M_PI
#define M_PI 3.14159265358979323846
#endif

#define KINGEN_UNREACHABLE 0
#define KINGEN_DIRECT_SINGULARITY 2
#define KINGEN_COLLISION 3
#define KINGEN_NONE 4
#define KINGEN_RADICAND_BAND 1e-5
#define KINGEN_TRANSLATION_SINGULAR 1e-12

typedef struct {
    double pivot[6][3];        /* A_i */
    double cos_direction[6];   /* cos(beta_i), sin(beta_i) */
    double sin_direction[6];
    double crank_length[6];    /* r_i */
    double rod_length[6];      /* L_i */
    double platform[6][3];     /* c_i, platform frame */
    int branch[6];             /* 0: theta = phi + acos(K / rho), 1: minus */
    double home[6];            /* x y z (mm) roll pitch yaw (rad) */
    double index_threshold;    /* mm; <= 0: no direct-index rule */
    double home_det_sign;      /* +1, -1; 0: no sign rule */
    int euler;                 /* 1: roll = k cos a, pitch = k sin a; 0: about (cos a, sin a, 0) */
    int collision;             /* 0 none, 1 segments (all pairs, cranks at their angle), 2 thesis */
    double rod_radius, crank_radius;
    int cranks_collide_at_zero; /* thesis model: the static crank check failed */
} kingen_design;

static void rotation_rpy(double roll, double pitch, double yaw, double R[3][3])
{
    double cr = cos(roll), sr = sin(roll), cp = cos(pitch), sp = sin(pitch), cy = cos(yaw), sy = sin(yaw);
    R[0][0] = cy * cp; R[0][1] = cy * sp * sr - sy * cr; R[0][2] = cy * sp * cr + sy * sr;
    R[1][0] = sy * cp; R[1][1] = sy * sp * sr + cy * cr; R[1][2] = sy * sp * cr - cy * sr;
    R[2][0] = -sp;     R[2][1] = cp * sr;                R[2][2] = cp * cr;
}

static void rotation_axis(double ax, double ay, double angle, const double home[3][3], double R[3][3])
{
    /* Rodrigues: I + sin K + (1 - cos) K^2, K = [axis]x, axis (ax, ay, 0); then times home. */
    double s = sin(angle), c1 = 1.0 - cos(angle), T[3][3];
    int i, j;
    T[0][0] = 1.0 - c1 * ay * ay; T[0][1] = c1 * ax * ay;        T[0][2] = s * ay;
    T[1][0] = c1 * ax * ay;       T[1][1] = 1.0 - c1 * ax * ax;  T[1][2] = -s * ax;
    T[2][0] = -s * ay;            T[2][1] = s * ax;              T[2][2] = 1.0 - c1 * (ax * ax + ay * ay);
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            R[i][j] = T[i][0] * home[0][j] + T[i][1] * home[1][j] + T[i][2] * home[2][j];
}

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static double segment_distance(const double p1[3], const double q1[3], const double p2[3], const double q2[3])
{
    /* Ericson, Real-Time Collision Detection 5.1.9, as kingen/collision.py. */
    double d1[3], d2[3], r[3], a, e, f, c, b, denominator, s, t, x[3];
    int k;
    for (k = 0; k < 3; k++) { d1[k] = q1[k] - p1[k]; d2[k] = q2[k] - p2[k]; r[k] = p1[k] - p2[k]; }
    a = dot3(d1, d1); e = dot3(d2, d2); f = dot3(d2, r); c = dot3(d1, r); b = dot3(d1, d2);
    denominator = a * e - b * b;
    s = 0.0;
    if (denominator > 1e-12 * a * e) {
        s = (b * f - c * e) / denominator;
        s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    }
    t = e > 0 ? (b * s + f) / e : 0.0;
    if (t < 0.0) {
        s = a > 0 ? -c / a : 0.0;
        s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    } else if (t > 1.0) {
        s = a > 0 ? (b - c) / a : 0.0;
        s = s < 0.0 ? 0.0 : (s > 1.0 ? 1.0 : s);
    }
    t = t < 0.0 ? 0.0 : (t > 1.0 ? 1.0 : t);
    for (k = 0; k < 3; k++)
        x[k] = p1[k] + d1[k] * s - (p2[k] + d2[k] * t);
    return sqrt(dot3(x, x));
}

static double line_distance(const double p1[3], const double q1[3], const double p2[3], const double q2[3])
{
    double d1[3], d2[3], r[3], n[3], length, along[3];
    int k;
    for (k = 0; k < 3; k++) { d1[k] = q1[k] - p1[k]; d2[k] = q2[k] - p2[k]; r[k] = p2[k] - p1[k]; }
    n[0] = d1[1] * d2[2] - d1[2] * d2[1]; n[1] = d1[2] * d2[0] - d1[0] * d2[2]; n[2] = d1[0] * d2[1] - d1[1] * d2[0];
    length = sqrt(dot3(n, n));
    if (length <= 1e-12 * sqrt(dot3(d1, d1)) * sqrt(dot3(d2, d2))) {
        along[0] = r[1] * d1[2] - r[2] * d1[1]; along[1] = r[2] * d1[0] - r[0] * d1[2]; along[2] = r[0] * d1[1] - r[1] * d1[0];
        return sqrt(dot3(along, along)) / sqrt(dot3(d1, d1));
    }
    return fabs(dot3(r, n)) / length;
}

static int determinant_sign(double W[6][6])
{
    /* LU with partial pivoting; the sign of the product of the pivots and the swaps. */
    double A[6][6], m;
    int i, j, k, p, sign = 1;
    for (i = 0; i < 6; i++)
        for (j = 0; j < 6; j++)
            A[i][j] = W[i][j];
    for (k = 0; k < 6; k++) {
        p = k;
        for (i = k + 1; i < 6; i++)
            if (fabs(A[i][k]) > fabs(A[p][k]))
                p = i;
        if (A[p][k] == 0.0)
            return 0;
        if (p != k) {
            for (j = 0; j < 6; j++) { m = A[k][j]; A[k][j] = A[p][j]; A[p][j] = m; }
            sign = -sign;
        }
        if (A[k][k] < 0.0)
            sign = -sign;
        for (i = k + 1; i < 6; i++) {
            m = A[i][k] / A[k][k];
            for (j = k + 1; j < 6; j++)
                A[i][j] -= m * A[k][j];
        }
    }
    return sign;
}

/* M = W^T W's lower triangle (j <= i), M = sum_i w_i w_i^T over the limbs' unit wrenches. */
static void gram(double W[6][6], double M[6][6])
{
    int i, j, k;
    for (i = 0; i < 6; i++)
        for (j = 0; j <= i; j++) {
            double sum = 0.0;
            for (k = 0; k < 6; k++)
                sum += W[k][i] * W[k][j];
            M[i][j] = sum;
        }
}

static int index_above(double W[6][6], double threshold)
{
    /* Whether the direct index exceeds threshold: M - threshold^2 diag(0, 0, 0, 1, 1, 1)
     * positive definite (LDL^T pivots all positive), M = sum_i w_i w_i^T; false when M_vv is
     * singular (kingen/singularity.py's translation singularity). */
    double M[6][6], pivot[6], trace;
    int i, j, k;
    gram(W, M);
    trace = M[0][0] + M[1][1] + M[2][2];
    for (i = 3; i < 6; i++)
        M[i][i] -= threshold * threshold;
    for (j = 0; j < 6; j++) {
        double d = M[j][j];
        for (k = 0; k < j; k++)
            d -= M[j][k] * M[j][k] * pivot[k];
        pivot[j] = d;
        if (j == 2 && !(pivot[0] * pivot[1] * pivot[2] > KINGEN_TRANSLATION_SINGULAR * (trace / 3.0) * (trace / 3.0) * (trace / 3.0)))
            return 0;
        if (!(d > 0.0))
            return 0;
        for (i = j + 1; i < 6; i++) {
            double l = M[i][j];
            for (k = 0; k < j; k++)
                l -= M[i][k] * M[j][k] * pivot[k];
            M[i][j] = l / d;
        }
    }
    return 1;
}

/* The crank tips and platform points (base frame) and the unit wrenches W of the pose R, p
 * (mm); 0 when a limb is unreachable or at its own singularity (D <= 1e-5). */
static int assemble(const kingen_design *design, double R[3][3], const double p[3], double tip[6][3],
                    double point[6][3], double W[6][6])
{
    int i, k;
    for (i = 0; i < 6; i++) {
        const double *c = design->platform[i], *A = design->pivot[i];
        double g[3], a, b, kk, rho2, D, rho, cos_phi, sin_phi, cos_half, sin_half, ct, st, f[3], n;
        double r = design->crank_length[i], L = design->rod_length[i];
        for (k = 0; k < 3; k++)
            point[i][k] = R[k][0] * c[0] + R[k][1] * c[1] + R[k][2] * c[2] + p[k];
        for (k = 0; k < 3; k++)
            g[k] = point[i][k] - A[k];
        a = g[0] * design->cos_direction[i] + g[1] * design->sin_direction[i];
        b = -g[2];
        kk = (dot3(g, g) + r * r - L * L) / (2.0 * r);
        rho2 = a * a + b * b;
        D = rho2 > 0.0 ? (rho2 - kk * kk) / rho2 : -1.0;
        if (!(D > KINGEN_RADICAND_BAND))
            return 0;
        rho = sqrt(rho2);
        cos_phi = a / rho; sin_phi = b / rho; cos_half = kk / rho; sin_half = sqrt(D);
        if (design->branch[i] == 0) {
            ct = cos_phi * cos_half - sin_phi * sin_half;
            st = sin_phi * cos_half + cos_phi * sin_half;
        } else {
            ct = cos_phi * cos_half + sin_phi * sin_half;
            st = sin_phi * cos_half - cos_phi * sin_half;
        }
        tip[i][0] = A[0] + r * ct * design->cos_direction[i];
        tip[i][1] = A[1] + r * ct * design->sin_direction[i];
        tip[i][2] = A[2] - r * st;
        for (k = 0; k < 3; k++)
            f[k] = point[i][k] - tip[i][k];
        n = sqrt(dot3(f, f));
        for (k = 0; k < 3; k++)
            W[i][k] = f[k] / n;
        W[i][3] = point[i][1] * W[i][2] - point[i][2] * W[i][1];
        W[i][4] = point[i][2] * W[i][0] - point[i][0] * W[i][2];
        W[i][5] = point[i][0] * W[i][1] - point[i][1] * W[i][0];
    }
    return 1;
}

/* What stops the pose R, p (mm): a KINGEN_* cause. */
static int judge_pose(const kingen_design *design, double R[3][3], const double p[3])
{
    double tip[6][3], point[6][3], W[6][6];
    int i, k, collide = design->cranks_collide_at_zero;
    if (!assemble(design, R, p, tip, point, W))
        return KINGEN_UNREACHABLE;
    if (design->home_det_sign != 0.0 && determinant_sign(W) != (int)design->home_det_sign)
        return KINGEN_DIRECT_SINGULARITY;
    if (design->index_threshold > 0.0 && !index_above(W, design->index_threshold))
        return KINGEN_DIRECT_SINGULARITY;
    if (design->collision == 2) {
        static const int pairs[3][2] = {{0, 5}, {1, 2}, {3, 4}};
        for (k = 0; k < 3 && !collide; k++)
            collide = line_distance(tip[pairs[k][0]], point[pairs[k][0]], tip[pairs[k][1]], point[pairs[k][1]])
                      - 2.0 * design->rod_radius < 0.0;
    } else if (design->collision == 1) {
        int j;
        for (i = 0; i < 6 && !collide; i++)
            for (j = i + 1; j < 6 && !collide; j++)
                collide = segment_distance(tip[i], point[i], tip[j], point[j]) - 2.0 * design->rod_radius < 0.0
                          || segment_distance(design->pivot[i], tip[i], design->pivot[j], tip[j])
                             - 2.0 * design->crank_radius < 0.0;
    }
    return collide ? KINGEN_COLLISION : KINGEN_NONE;
}

/* The direct index (mm) at home and the sign of det W there (0: unreachable or singular),
 * as kingen/singularity.py computes them: the Schur complement S = M_ww - M_wv M_vv^-1 M_vw
 * of M = W^T W and the square root of its smallest eigenvalue in closed form (0 where M_vv is
 * singular); and whether the thesis's cranks, held at angle 0, come closer than their radii
 * for the pairs (1, 6), (2, 3), (4, 5). */
void kingen_home(const kingen_design *design, double *index, double *det_sign, int *cranks_collide_at_zero)
{
    static const int pairs[3][2] = {{0, 5}, {1, 2}, {3, 4}};
    double R[3][3], tip[6][3], point[6][3], W[6][6], M[6][6], S[3][3], X[3][3], trace, mean, off, spread, half, angle;
    double b00, b11, b22, determinant, zero_tips[6][3];
    int i, j, k;
    for (i = 0; i < 6; i++) {
        zero_tips[i][0] = design->pivot[i][0] + design->crank_length[i] * design->cos_direction[i];
        zero_tips[i][1] = design->pivot[i][1] + design->crank_length[i] * design->sin_direction[i];
        zero_tips[i][2] = design->pivot[i][2];
    }
    *cranks_collide_at_zero = 0;
    for (k = 0; k < 3; k++)
        *cranks_collide_at_zero |= segment_distance(design->pivot[pairs[k][0]], zero_tips[pairs[k][0]],
                                                    design->pivot[pairs[k][1]], zero_tips[pairs[k][1]])
                                   - 2.0 * design->crank_radius < 0.0;
    rotation_rpy(design->home[3], design->home[4], design->home[5], R);
    *index = NAN;
    *det_sign = 0.0;
    if (!assemble(design, R, design->home, tip, point, W))
        return;
    *det_sign = determinant_sign(W);
    gram(W, M);
    for (i = 0; i < 6; i++)
        for (j = i + 1; j < 6; j++)
            M[i][j] = M[j][i];
    trace = M[0][0] + M[1][1] + M[2][2];
    {
        /* M_vv^-1 M_vw by Gaussian elimination of the 3x3 force block. */
        double A[3][6], pivot, product = 1.0;
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++) { A[i][j] = M[i][j]; A[i][3 + j] = M[i][3 + j]; }
        for (k = 0; k < 3; k++) {
            pivot = A[k][k];
            product *= pivot;
            if (k == 2 && !(product > KINGEN_TRANSLATION_SINGULAR * (trace / 3.0) * (trace / 3.0) * (trace / 3.0))) {
                *index = 0.0;
                return;
            }
            for (i = 0; i < 3; i++) {
                double m;
                if (i == k)
                    continue;
                m = A[i][k] / pivot;
                for (j = k; j < 6; j++)
                    A[i][j] -= m * A[k][j];
            }
        }
        for (i = 0; i < 3; i++)
            for (j = 0; j < 3; j++)
                X[i][j] = A[i][3 + j] / A[i][i];
    }
    for (i = 0; i < 3; i++)
        for (j = 0; j < 3; j++)
            S[i][j] = M[3 + i][3 + j] - (M[3 + i][0] * X[0][j] + M[3 + i][1] * X[1][j] + M[3 + i][2] * X[2][j]);
    off = S[0][1] * S[0][1] + S[0][2] * S[0][2] + S[1][2] * S[1][2];
    mean = (S[0][0] + S[1][1] + S[2][2]) / 3.0;
    b00 = S[0][0] - mean; b11 = S[1][1] - mean; b22 = S[2][2] - mean;
    determinant = b00 * (b11 * b22 - S[1][2] * S[1][2]) - S[0][1] * (S[0][1] * b22 - S[1][2] * S[0][2])
                  + S[0][2] * (S[0][1] * S[1][2] - b11 * S[0][2]);
    spread = sqrt((b00 * b00 + b11 * b11 + b22 * b22 + 2.0 * off) / 6.0);
    half = spread > 0.0 ? determinant / (2.0 * spread * spread * spread) : 1.0;
    half = half > 1.0 ? 1.0 : (half < -1.0 ? -1.0 : half);
    angle = acos(half) / 3.0;
    mean += 2.0 * spread * cos(angle + 2.0 * M_PI / 3.0);
    *index = sqrt(mean > 0.0 ? mean : 0.0);
}

/* For each azimuth a (radians): the index of the first tilt (tilts, radians, ascending from
 * 0) that some check stops, or count_tilts if none does, and what stops it (KINGEN_NONE if
 * nothing). Returns the number of poses judged. */
long kingen_tilt_table(const kingen_design *design, const double *azimuths, int count_azimuths,
                       const double *tilts, int count_tilts, int *first_stop, int *cause)
{
    double home[3][3], R[3][3];
    long judged = 0;
    int n, k;
    rotation_rpy(design->home[3], design->home[4], design->home[5], home);
    for (n = 0; n < count_azimuths; n++) {
        double ca = cos(azimuths[n]), sa = sin(azimuths[n]);
        first_stop[n] = count_tilts;
        cause[n] = KINGEN_NONE;
        for (k = 0; k < count_tilts; k++) {
            int verdict;
            if (design->euler)
                rotation_rpy(design->home[3] + tilts[k] * ca, design->home[4] + tilts[k] * sa, design->home[5], R);
            else
                rotation_axis(ca, sa, tilts[k], home, R);
            verdict = judge_pose(design, R, design->home);
            judged++;
            if (verdict != KINGEN_NONE) {
                first_stop[n] = k;
                cause[n] = verdict;
                break;
            }
        }
    }
    return judged;
}
