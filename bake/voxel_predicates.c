/*
 * voxel_predicates.c — the voxelizer's exact geometric predicates: Shewchuk's
 * orient2d / orient3d ("Adaptive Precision Floating-Point Arithmetic and Fast
 * Robust Geometric Predicates", 1997: static filters, then the exact sign
 * from expansion arithmetic), and the signs for the perturbed query
 * q* = q + (delta, eps, eps^2) of voxelize.h (Edelsbrunner & Muecke's
 * simulation of simplicity, applied to the query only), so that a ray from
 * q* meets no vertex or edge and every crossing is a clean one.
 */
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "voxelize_internal.h"

/* >>exact predicates -----------------------------------------------------------
 * Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
 * Geometric Predicates" (1997): the static filters of orient2d / orient3d
 * (ccwerrboundA, o3derrboundA) and, when they cannot decide, the exact
 * determinant as a nonoverlapping expansion (grow / scale with zero
 * elimination; products by Dekker splitting). Non-adaptive: the exact branch
 * is rare (counted in stats.exact_predicates), so it favours brevity. */

#define EPS 0x1p-53
#define SPLITTER 134217729.0 /* 2^27 + 1 */
static const double ccw_bound = (3.0 + 16.0 * EPS) * EPS;
static const double o3d_bound = (7.0 + 56.0 * EPS) * EPS;

static void two_sum(double a, double b, double* x, double* y)
{
    const double s = a + b, bv = s - a, av = s - bv;
    *x = s;
    *y = (a - av) + (b - bv);
}

static void two_diff(double a, double b, double e[2]) /* e = {low, high}: a - b exactly */
{
    const double s = a - b, bv = a - s, av = s + bv;
    e[1] = s;
    e[0] = (a - av) + (bv - b);
}

static void split(double a, double* hi, double* lo)
{
    const double c = SPLITTER * a, big = c - a;
    *hi = c - big;
    *lo = a - *hi;
}

static void two_product_presplit(double a, double b, double bhi, double blo, double* x, double* y)
{
    double ahi, alo;
    *x = a * b;
    split(a, &ahi, &alo);
    const double e1 = *x - ahi * bhi, e2 = e1 - alo * bhi, e3 = e2 - ahi * blo;
    *y = alo * blo - e3;
}

/* h = e + b; h may be e. Returns the length of h. */
static int grow(int n, const double* e, double b, double* h)
{
    double q = b;
    int m = 0;
    for (int i = 0; i < n; ++i) {
        double s, t;
        two_sum(q, e[i], &s, &t);
        if (t != 0.0)
            h[m++] = t;
        q = s;
    }
    if (q != 0.0 || m == 0)
        h[m++] = q;
    return m;
}

/* h = e * b (h must not be e). */
static int scale(int n, const double* e, double b, double* h)
{
    double bhi, blo, q, hh;
    split(b, &bhi, &blo);
    int m = 0;
    two_product_presplit(e[0], b, bhi, blo, &q, &hh);
    if (hh != 0.0)
        h[m++] = hh;
    for (int i = 1; i < n; ++i) {
        double p1, p0, s;
        two_product_presplit(e[i], b, bhi, blo, &p1, &p0);
        two_sum(q, p0, &s, &hh);
        if (hh != 0.0)
            h[m++] = hh;
        q = p1 + s; /* fast two-sum: |p1| >= |s| */
        hh = s - (q - p1);
        if (hh != 0.0)
            h[m++] = hh;
    }
    if (q != 0.0 || m == 0)
        h[m++] = q;
    return m;
}

/* h = e * f, f of length <= 2 (every factor here is a difference). */
static int mul2(int n, const double* e, const double f[2], double* h)
{
    double t[512];
    int m = scale(n, e, f[1], h);
    if (f[0] != 0.0) {
        const int k = scale(n, e, f[0], t);
        for (int i = 0; i < k; ++i)
            m = grow(m, h, t[i], h);
    }
    return m;
}

/* h = e - f. */
static int sub(int n, const double* e, int k, const double* f, double* h)
{
    memcpy(h, e, sizeof(double) * (size_t)n);
    for (int i = 0; i < k; ++i)
        n = grow(n, h, -f[i], h);
    return n;
}

static int sgn(double v)
{
    return (v > 0.0) - (v < 0.0);
}

/* Sign of (a - c) x (b - c) in the coordinates (u, v) = (p[U], p[V]). */
static int orient2d_exact(double au, double av, double bu, double bv, double cu, double cv)
{
    double acu[2], bcv[2], acv[2], bcu[2], l[8], r[8], d[16];
    two_diff(au, cu, acu);
    two_diff(bv, cv, bcv);
    two_diff(av, cv, acv);
    two_diff(bu, cu, bcu);
    const int nl = mul2(2, acu, bcv, l), nr = mul2(2, acv, bcu, r);
    const int nd = sub(nl, l, nr, r, d);
    return sgn(d[nd - 1]);
}

static int orient2d(double au, double av, double bu, double bv, double cu, double cv, uint64_t* exact)
{
    const double dl = (au - cu) * (bv - cv), dr = (av - cv) * (bu - cu), det = dl - dr;
    double sum;
    if (dl > 0.0) {
        if (dr <= 0.0)
            return sgn(det);
        sum = dl + dr;
    } else if (dl < 0.0) {
        if (dr >= 0.0)
            return sgn(det);
        sum = -dl - dr;
    } else {
        return sgn(det);
    }
    const double bound = ccw_bound * sum;
    if (det >= bound || -det >= bound)
        return sgn(det);
    ++*exact;
    return orient2d_exact(au, av, bu, bv, cu, cv);
}

/* Sign of det[a - d; b - d; c - d] (Shewchuk's orient3d: positive when d is
 * behind the plane of a, b, c as seen with a, b, c counter-clockwise). */
static int orient3d_exact(const double* a, const double* b, const double* c, const double* d)
{
    double A[3][2], B[3][2], C[3][2];
    for (int k = 0; k < 3; ++k) {
        two_diff(a[k], d[k], A[k]);
        two_diff(b[k], d[k], B[k]);
        two_diff(c[k], d[k], C[k]);
    }
    double acc[256], p[8], q[8], minor[16], term[64];
    int n = 0;
    for (int k = 0; k < 3; ++k) { /* A_k (B_k1 C_k2 - B_k2 C_k1), (k, k1, k2) cyclic */
        const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
        const int np = mul2(2, B[k1], C[k2], p), nq = mul2(2, B[k2], C[k1], q);
        const int nm = sub(np, p, nq, q, minor);
        const int nt = mul2(nm, minor, A[k], term);
        for (int i = 0; i < nt; ++i)
            n = grow(n, acc, term[i], acc);
    }
    return sgn(acc[n - 1]);
}

static int orient3d(const double* a, const double* b, const double* c, const double* d, uint64_t* exact)
{
    const double adx = a[0] - d[0], bdx = b[0] - d[0], cdx = c[0] - d[0];
    const double ady = a[1] - d[1], bdy = b[1] - d[1], cdy = c[1] - d[1];
    const double adz = a[2] - d[2], bdz = b[2] - d[2], cdz = c[2] - d[2];
    const double bc = bdx * cdy, cb = cdx * bdy, ca = cdx * ady, ac = adx * cdy, ab = adx * bdy, ba = bdx * ady;
    const double det = adz * (bc - cb) + bdz * (ca - ac) + cdz * (ab - ba);
    const double perm =
        (fabs(bc) + fabs(cb)) * fabs(adz) + (fabs(ca) + fabs(ac)) * fabs(bdz) + (fabs(ab) + fabs(ba)) * fabs(cdz);
    const double bound = o3d_bound * perm;
    if (det > bound || -det > bound)
        return sgn(det);
    ++*exact;
    return orient3d_exact(a, b, c, d);
}

/* >>perturbed predicates ---------------------------------------------------------
 * The query q* = q + (delta, eps, eps^2) of voxelize.h. */

/* Side of q* against the projected edge a -> b in the (y, z) plane:
 * orient2d(a, b, q*) = orient2d(a, b, q) + eps (a_z - b_z) + eps^2 (b_y - a_y). */
int mesoi_edge_side(const double* a, const double* b, const double* q, uint64_t* exact)
{
    const int s = orient2d(a[1], a[2], b[1], b[2], q[1], q[2], exact);
    if (s)
        return s;
    if (a[2] != b[2])
        return a[2] > b[2] ? 1 : -1;
    return b[1] > a[1] ? 1 : b[1] < a[1] ? -1 : 0;
}

/* Sign of orient3d(a, b, c, q*) = n.(a - q*) with n = (b - a) x (c - a):
 * orient3d(a, b, c, q) - delta n_x - eps n_y - eps^2 n_z. 0 only when the
 * triangle is degenerate. */
int mesoi_side3(const double* a, const double* b, const double* c, const double* q, uint64_t* exact)
{
    const int s = orient3d(a, b, c, q, exact);
    if (s)
        return s;
    static const int uv[3][2] = {{1, 2}, {2, 0}, {0, 1}}; /* n_x, n_y, n_z as 2D orientations */
    for (int k = 0; k < 3; ++k) {
        const int u = uv[k][0], v = uv[k][1];
        const int nk = orient2d(a[u], a[v], b[u], b[v], c[u], c[v], exact);
        if (nk)
            return -nk;
    }
    return 0;
}
