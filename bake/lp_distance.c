/* lp_distance.c — Lp-averaged distance d_p of a mesh and its gradient:
 * closed-form p = 3 triangle integrals, adaptive quadrature for other p, and a
 * Barnes–Hut tree (paper §4.1–4.2). Derivations are in lp_distance.h. */
#include "lp_distance.h"
#include "vec3d.h"

#include <float.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

/* Triangles per BVH leaf: small leaves let the per-triangle far rule take
 * over early. 4 is the usual BVH choice, not tuned here. */
#define LEAF_SIZE 4u
/* Traversal stack: a median-split tree over < 2^32 triangles is < 33 deep and
 * holds at most one pending sibling per level. */
#define STACK_DEPTH 80
/* Depth cap of the 1-D adaptive quadrature (p != 3): a feature of width w
 * needs ~log2(1/w) halvings, so 40 reaches far below double resolution. */
#define QUAD_MAX_DEPTH 40

typedef struct lp_node {
    double c[3];    /* area-weighted centroid (scaled units) */
    double radius;  /* max distance of a vertex of the node's triangles from c */
    double area;
    double m[6];    /* ∫ (y−c)(y−c)ᵀ dy: xx yy zz xy xz yz */
    uint32_t right; /* index of the second child (the first is this + 1); 0 for a leaf */
    uint32_t first; /* leaf: triangle range in tree order */
    uint32_t count;
} lp_node;

struct meso_lp_field {
    meso_lp_options opt;
    double origin[3]; /* bounding-box centre (mesh units) */
    double scale;     /* bounding-box diagonal: mesh units per internal unit */
    double area;      /* total area, internal units */
    int pint;         /* p when it is an integer, else 0 (fast powers) */
    uint32_t nt;
    uint32_t node_count;
    double* tri;      /* 9 doubles per triangle in tree order, internal units */
    double* sphere;   /* 5 per triangle in tree order: centroid, bounding radius about it, area */
    lp_node* nodes;
    _Atomic uint64_t unsplit_opened; /* >>regions: evaluations that opened a cluster left unsplit */
};

/* >>small vector helpers ------------------------------------------------- */

/* r^−p from 1/r² (pint: p as an integer or 0): integer p avoids pow(), which
 * dominates the quadrature and far-field cost otherwise. The far field's
 * callers take the further powers r^−p−2k by multiplying with 1/r², so a
 * far term costs one division and (p odd) one square root, not the four
 * divisions that were most of an evaluation's time. */
static inline double inv_pow_from_inverse(double inv_r2, double p, int pint)
{
    if (pint > 0) {
        double q = 1.0;
        for (int k = 0; k < pint / 2; ++k)
            q *= inv_r2;
        if (pint & 1)
            q *= sqrt(inv_r2);
        return q;
    }
    return pow(inv_r2, 0.5 * p);
}

/* r^−p from r². */
static inline double inv_pow(double r2, double p, int pint)
{
    return inv_pow_from_inverse(1.0 / r2, p, pint);
}

/* >>p = 3 closed form ----------------------------------------------------- */

/* F(t) = atan(t)/t and F'(t), t in [0, 1]. Series below 0.1: the terms fall
 * by t² ≤ 0.01, so 8 terms reach double precision; above it the direct forms
 * lose at most ~2 digits in F' (F' = (1/(1+t²) − F)/t cancels). */
static void atanc(double t, double* F, double* Fp)
{
    if (t < 0.1) {
        double t2 = t * t, f = 0.0, fp = 0.0;
        for (int k = 8; k >= 1; --k) {
            double sgn = (k & 1) ? -1.0 : 1.0;
            f = f * t2 + sgn / (2.0 * k + 1.0);
            fp = fp * t2 + sgn * 2.0 * k / (2.0 * k + 1.0);
        }
        *F = 1.0 + t2 * f; /* 1 − t²/3 + t⁴/5 − … */
        *Fp = t * fp;      /* −2t/3 + 4t³/5 − … */
        return;
    }
    double at = atan(t);
    *F = at / t;
    *Fp = (1.0 / (1.0 + t * t) - *F) / t;
}

double meso_lp_triangle_p3(const double a[3], const double b[3], const double c[3], const double x[3], double j[3])
{
    double u[3], v[3], w[3], e1[3], e2[3], cr[3];
    sub3(a, x, u);
    sub3(b, x, v);
    sub3(c, x, w);
    sub3(b, a, e1);
    sub3(c, a, e2);
    cross3(e1, e2, cr);
    if (j)
        j[0] = j[1] = j[2] = 0.0;
    double two_area = sqrt(dot3(cr, cr));
    if (!(two_area > 0.0))
        return 0.0;
    double n[3] = {cr[0] / two_area, cr[1] / two_area, cr[2] / two_area};
    double hs = -dot3(n, u); /* signed height of x above the plane */
    double hh = fabs(hs), sg = hs < 0.0 ? -1.0 : 1.0;
    double lu = sqrt(dot3(u, u)), lv = sqrt(dot3(v, v)), lw = sqrt(dot3(w, w));
    double uv = dot3(u, v), uw = dot3(u, w), vw = dot3(v, w);
    double D = lu * lv * lw + uv * lw + uw * lv + vw * lu;
    double Y = two_area * hh; /* |u·(v×w)| */
    int series = D > 0.0 && Y <= D;
    if (!series && hh == 0.0)
        return INFINITY; /* in the plane with D <= 0: on the closed triangle */
    double I, t = 0.0, F = 1.0, Fp = 0.0, theta = 0.0;
    if (series) {
        t = Y / D;
        atanc(t, &F, &Fp);
        I = 2.0 * two_area * F / D;
    } else {
        theta = atan2(Y, D);
        I = 2.0 * theta / hh;
    }
    if (!j)
        return I;
    /* ∇_x D (u, v, w all have ∂/∂x = −identity). */
    double gD[3];
    for (int k = 0; k < 3; ++k)
        gD[k] = -(u[k] / lu * lv * lw + v[k] / lv * lu * lw + w[k] / lw * lu * lv + (u[k] + v[k]) * lw +
                  uv * w[k] / lw + (u[k] + w[k]) * lv + uw * v[k] / lv + (v[k] + w[k]) * lu + vw * u[k] / lu);
    double gI[3];
    for (int k = 0; k < 3; ++k) {
        double gh = sg * n[k], gY = two_area * gh;
        if (series) {
            double gt = (gY - t * gD[k]) / D;
            gI[k] = 2.0 * two_area * (Fp * gt / D - F * gD[k] / (D * D));
        } else {
            double gth = (D * gY - Y * gD[k]) / (Y * Y + D * D);
            gI[k] = 2.0 * gth / hh - 2.0 * theta * gh / (hh * hh);
        }
    }
    /* ∫ (x−y) r^−5 = −(1/3) ∇_x ∫ r^−3 */
    for (int k = 0; k < 3; ++k)
        j[k] = -gI[k] / 3.0;
    return I;
}

/* >>polar quadrature (any p > 2) ------------------------------------------
 * With x0 the foot of x on T's plane and h = |x − x0|, split T into the signed
 * sub-triangles (x0, P, Q) of its edges and integrate in polar coordinates
 * about x0. The radial integral is elementary,
 *   ∫_0^R ρ (ρ²+h²)^(−q/2) dρ = G(R) = (h^(2−q) − (R²+h²)^(1−q/2)) / (q−2),
 * leaving per edge a smooth 1-D integral over the polar angle ψ measured from
 * the foot of x0 on the edge line (distance δ, so R = δ / cos ψ):
 *   I_q = Σ_e σ_e ∫ G(δ_e / cos ψ) dψ.
 * When x0 is outside T the h^(2−q) parts cancel exactly (the signed angles sum
 * to 0), so they are dropped instead of cancelled numerically; otherwise G is
 * evaluated as −h^(2−q) expm1((1−q/2) log1p(R²/h²)) / (q−2), free of
 * cancellation. The gradient integral is split along n and the plane:
 *   J·n = h_signed · I_(p+2),
 *   J_∥ = (1/p) ∮_∂T |x−y|^−p ν ds     (ν: outward edge normal in the plane;
 * from ∇_∥ ∫_T f(x−y) dy = −∮ f ν ds, the divergence theorem), and on each
 * edge t = c·tan α (c: distance of x to the edge line) turns the line
 * integral into c^(1−p) ∫ cos^(p−2) α dα. Every 1-D integral is adaptive
 * 5-point Gauss–Legendre (halve until both halves agree with the whole to
 * rel_tol). A near-singular triangle costs ~100–300 kernel evaluations. */

typedef struct quad_ctx {
    const double* x;
    double p;
    int pint;
} quad_ctx;

enum { LINE_G, LINE_SPLIT, LINE_COS };

typedef struct line_fn {
    int kind;
    double d2, h2; /* squared distance of x0 to the edge line, squared height */
    double q[2];   /* exponents p and p + 2 (LINE_G / LINE_SPLIT); p for LINE_COS */
    int qint[2];   /* the same as integers, or 0 */
    int nq;
} line_fn;

static void line_eval(const line_fn* f, double s, double out[2])
{
    if (f->kind == LINE_COS) {
        double cs = cos(s);
        out[0] = f->qint[0] > 0 ? 1.0 / inv_pow(cs * cs, f->q[0] - 2.0, f->qint[0] - 2) : pow(cs, f->q[0] - 2.0);
        return;
    }
    double tn = tan(s), R2 = f->d2 * (1.0 + tn * tn);
    for (int k = 0; k < f->nq; ++k) {
        double e = f->q[k] - 2.0;
        int ei = f->qint[k] > 0 ? f->qint[k] - 2 : 0;
        if (f->kind == LINE_SPLIT)
            out[k] = inv_pow(R2 + f->h2, e, ei); /* (R²+h²)^(1−q/2) */
        else
            out[k] = -inv_pow(f->h2, e, ei) * expm1(-0.5 * e * log1p(R2 / f->h2)) / e;
    }
}

static void gl5(const line_fn* f, double a, double b, double out[2])
{
    static const double xs[5] = {0.0, -0.5384693101056831, 0.5384693101056831, -0.9061798459386640,
                                 0.9061798459386640};
    static const double ws[5] = {0.5688888888888889, 0.4786286704993665, 0.4786286704993665, 0.2369268850561891,
                                 0.2369268850561891};
    double m = 0.5 * (a + b), r = 0.5 * (b - a), v[2];
    out[0] = out[1] = 0.0;
    for (int i = 0; i < 5; ++i) {
        line_eval(f, m + r * xs[i], v);
        for (int k = 0; k < f->nq; ++k)
            out[k] += ws[i] * r * v[k];
    }
}

static void gl_adapt(const line_fn* f, double a, double b, const double whole[2], double tol, int depth,
                     double acc[2])
{
    double m = 0.5 * (a + b), l[2], r[2];
    gl5(f, a, m, l);
    gl5(f, m, b, r);
    int ok = 1;
    for (int k = 0; k < f->nq; ++k)
        ok = ok && fabs(l[k] + r[k] - whole[k]) <= tol * fabs(l[k] + r[k]);
    if (ok || depth >= QUAD_MAX_DEPTH) {
        for (int k = 0; k < f->nq; ++k)
            acc[k] += l[k] + r[k];
        return;
    }
    gl_adapt(f, a, m, l, tol, depth + 1, acc);
    gl_adapt(f, m, b, r, tol, depth + 1, acc);
}

static void gl_integrate(const line_fn* f, double a, double b, double tol, double acc[2])
{
    double whole[2];
    acc[0] = acc[1] = 0.0;
    gl5(f, a, b, whole);
    gl_adapt(f, a, b, whole, tol, 0, acc);
}

/* Is x on the closed triangle (in its plane, inside or on an edge)? Same test
 * as the p = 3 closed form: h = 0 and the solid-angle denominator D <= 0. */
static int on_triangle(const double a[3], const double b[3], const double c[3], const double x[3])
{
    double u[3], v[3], w[3], e1[3], e2[3], cr[3];
    sub3(a, x, u);
    sub3(b, x, v);
    sub3(c, x, w);
    sub3(b, a, e1);
    sub3(c, a, e2);
    cross3(e1, e2, cr);
    if (dot3(u, cr) != 0.0)
        return 0;
    double lu = sqrt(dot3(u, u)), lv = sqrt(dot3(v, v)), lw = sqrt(dot3(w, w));
    double D = lu * lv * lw + dot3(u, v) * lw + dot3(u, w) * lv + dot3(v, w) * lu;
    return D <= 0.0 && dot3(cr, cr) > 0.0;
}

static double quad_triangle(const double a[3], const double b[3], const double c[3], const quad_ctx* q, double tol,
                            double j[3])
{
    const double* x = q->x;
    const double p = q->p;
    if (j)
        j[0] = j[1] = j[2] = 0.0;
    double e1[3], e2[3], cr[3];
    sub3(b, a, e1);
    sub3(c, a, e2);
    cross3(e1, e2, cr);
    double two_area = sqrt(dot3(cr, cr));
    if (!(two_area > 0.0))
        return 0.0;
    if (on_triangle(a, b, c, x))
        return INFINITY;
    double n[3] = {cr[0] / two_area, cr[1] / two_area, cr[2] / two_area}, xa[3];
    sub3(x, a, xa);
    double hs = dot3(n, xa), h = fabs(hs);
    double x0[3] = {x[0] - hs * n[0], x[1] - hs * n[1], x[2] - hs * n[2]};
    const double* vs[3] = {a, b, c};
    /* Signed angle the triangle subtends at x0: 0 outside, 2π inside, in
     * between only on the boundary. */
    double theta = 0.0;
    for (int e = 0; e < 3; ++e) {
        double pp[3], qq[3], pq[3];
        sub3(vs[e], x0, pp);
        sub3(vs[(e + 1) % 3], x0, qq);
        cross3(pp, qq, pq);
        theta += atan2(dot3(n, pq), dot3(pp, qq));
    }
    int split = fabs(theta) < 1e-9; /* x0 strictly outside */
    if (!split && h == 0.0)
        return INFINITY;
    int qi = q->pint;
    line_fn fa = {split ? LINE_SPLIT : LINE_G, 0.0, h * h, {p, p + 2.0}, {qi, qi ? qi + 2 : 0}, j ? 2 : 1};
    line_fn fc = {LINE_COS, 0.0, 0.0, {p, 0.0}, {qi, 0}, 1};
    double I[2] = {0.0, 0.0}, jp[3] = {0.0, 0.0, 0.0};
    for (int e = 0; e < 3; ++e) {
        const double* P = vs[e];
        const double* Q = vs[(e + 1) % 3];
        double pp[3], qq[3], pq[3], ed[3];
        sub3(P, x0, pp);
        sub3(Q, x0, qq);
        sub3(Q, P, ed);
        double L = sqrt(dot3(ed, ed));
        if (!(L > 0.0))
            continue;
        for (int k = 0; k < 3; ++k)
            ed[k] /= L;
        cross3(pp, qq, pq);
        double sc = dot3(n, pq), dist = fabs(sc) / L;
        double tP = dot3(pp, ed), tQ = dot3(qq, ed), acc[2];
        if (dist > 0.0) {
            fa.d2 = dist * dist;
            gl_integrate(&fa, atan2(tP, dist), atan2(tQ, dist), tol, acc);
            double sg = sc > 0.0 ? 1.0 : -1.0;
            for (int k = 0; k < fa.nq; ++k)
                I[k] += split ? -sg * acc[k] / (fa.q[k] - 2.0) : sg * acc[k];
        }
        if (j) {
            double cc = sqrt(dist * dist + h * h), E;
            if (cc > 0.0) {
                gl_integrate(&fc, atan2(tP, cc), atan2(tQ, cc), tol, acc);
                E = acc[0] * inv_pow(cc * cc, p - 1.0, qi ? qi - 1 : 0);
            } else { /* x on the edge line beyond the segment: ∫ |t|^−p dt */
                double lo = fmin(fabs(tP), fabs(tQ)), hi = fmax(fabs(tP), fabs(tQ));
                E = (inv_pow(lo * lo, p - 1.0, qi ? qi - 1 : 0) - inv_pow(hi * hi, p - 1.0, qi ? qi - 1 : 0)) /
                    (p - 1.0);
            }
            double nu[3];
            cross3(ed, n, nu); /* outward for counter-clockwise (a, b, c) about n */
            for (int k = 0; k < 3; ++k)
                jp[k] += nu[k] * E / p;
        }
    }
    if (j)
        for (int k = 0; k < 3; ++k)
            j[k] = jp[k] + hs * I[1] * n[k];
    return I[0];
}

double meso_lp_triangle_quad(const double a[3], const double b[3], const double c[3], const double x[3], double p,
                             double rel_tol, double j[3])
{
    if (!(p > 2.0)) {
        if (j)
            j[0] = j[1] = j[2] = NAN;
        return NAN;
    }
    quad_ctx q = {x, p, (p == floor(p) && p <= 64.0) ? (int)p : 0};
    return quad_triangle(a, b, c, &q, rel_tol > 0.0 ? rel_tol : MESO_LP_DEFAULT_QUAD_TOL, j);
}

/* >>tree build ------------------------------------------------------------ */

typedef struct sort_key {
    double key;
    uint32_t index;
} sort_key;

/* By key, ties by index: a total order, so the tree does not depend on the
 * sort's algorithm. */
static inline int key_less(const sort_key* a, const sort_key* b)
{
    return a->key < b->key || (a->key == b->key && a->index < b->index);
}

/* a[0..n) in key_less's order, by merge sort through tmp (n / 2 entries):
 * the same order qsort gave, and so the same tree; qsort's indirect
 * comparisons were most of the field stage of an update (issue 15 profile,
 * armadillo: the tree is rebuilt over every face). */
static void sort_keys(sort_key* a, sort_key* tmp, uint32_t n)
{
    if (n <= 16) {
        for (uint32_t i = 1; i < n; ++i) {
            const sort_key x = a[i];
            uint32_t j = i;
            for (; j > 0 && key_less(&x, &a[j - 1]); --j)
                a[j] = a[j - 1];
            a[j] = x;
        }
        return;
    }
    const uint32_t h = n / 2;
    sort_keys(a, tmp, h);
    sort_keys(a + h, tmp, n - h);
    if (!key_less(&a[h], &a[h - 1]))
        return; /* already in order */
    memcpy(tmp, a, sizeof(sort_key) * h);
    uint32_t i = 0, j = h, k = 0;
    while (i < h && j < n)
        a[k++] = key_less(&a[j], &tmp[i]) ? a[j++] : tmp[i++];
    while (i < h)
        a[k++] = tmp[i++];
}

typedef struct build_ctx {
    const double* tri;  /* 9 per triangle, input order */
    const double* cent; /* 3 per triangle */
    const double* area; /* per triangle */
    uint32_t* perm;     /* tree order -> input index */
    sort_key* keys; /* 2 x triangles: the keys, then sort_keys' scratch */
    lp_node* nodes;
    uint32_t count;
    int has_region;          /* >>regions: the box, internal units */
    double rlo[3], rhi[3], theta2;
} build_ctx;

/* Is node nd far (far_enough, no near ball) from every point of the
 * region? With 1e-9 of relative margin for the rounding of |x − c|². */
static int far_from_region(const build_ctx* b, const lp_node* nd)
{
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        const double e = fmax(fmax(b->rlo[k] - nd->c[k], nd->c[k] - b->rhi[k]), 0.0);
        d2 += e * e;
    }
    return nd->radius * nd->radius < b->theta2 * d2 * (1.0 - 1e-9);
}

/* Area, centroid, second moment and radius of triangles perm[first..+count). */
static void node_aggregate(const build_ctx* b, lp_node* nd, uint32_t first, uint32_t count)
{
    double area = 0.0, c[3] = {0, 0, 0}, plain[3] = {0, 0, 0};
    for (uint32_t i = first; i < first + count; ++i) {
        uint32_t t = b->perm[i];
        area += b->area[t];
        for (int k = 0; k < 3; ++k) {
            c[k] += b->area[t] * b->cent[3 * t + k];
            plain[k] += b->cent[3 * t + k];
        }
    }
    for (int k = 0; k < 3; ++k)
        c[k] = area > 0.0 ? c[k] / area : plain[k] / count;
    double m[6] = {0, 0, 0, 0, 0, 0}, r2max = 0.0;
    for (uint32_t i = first; i < first + count; ++i) {
        uint32_t t = b->perm[i];
        const double* g = b->cent + 3 * t;
        double at = b->area[t];
        /* Triangle about its centroid: (A/12) Σ_k d_k d_kᵀ (exact: the edge-
         * midpoint rule integrates quadratics, with m_k − g = −d_opposite/2);
         * then the parallel-axis shift A (g−c)(g−c)ᵀ. */
        double s[3];
        sub3(g, c, s);
        m[0] += at * s[0] * s[0];
        m[1] += at * s[1] * s[1];
        m[2] += at * s[2] * s[2];
        m[3] += at * s[0] * s[1];
        m[4] += at * s[0] * s[2];
        m[5] += at * s[1] * s[2];
        for (int v = 0; v < 3; ++v) {
            const double* p = b->tri + 9 * (size_t)t + 3 * v;
            double dd[3], dc[3];
            sub3(p, g, dd);
            double w = at / 12.0;
            m[0] += w * dd[0] * dd[0];
            m[1] += w * dd[1] * dd[1];
            m[2] += w * dd[2] * dd[2];
            m[3] += w * dd[0] * dd[1];
            m[4] += w * dd[0] * dd[2];
            m[5] += w * dd[1] * dd[2];
            sub3(p, c, dc);
            r2max = fmax(r2max, dot3(dc, dc));
        }
    }
    memcpy(nd->c, c, sizeof(c));
    memcpy(nd->m, m, sizeof(m));
    nd->area = area;
    nd->radius = sqrt(r2max);
}

static uint32_t build_node(build_ctx* b, uint32_t first, uint32_t count)
{
    uint32_t idx = b->count++;
    lp_node* nd = &b->nodes[idx];
    node_aggregate(b, nd, first, count);
    nd->first = first;
    nd->count = count;
    nd->right = 0;
    if (count <= LEAF_SIZE || (b->has_region && far_from_region(b, nd)))
        return idx;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = first; i < first + count; ++i)
        for (int k = 0; k < 3; ++k) {
            double v = b->cent[3 * b->perm[i] + k];
            lo[k] = fmin(lo[k], v);
            hi[k] = fmax(hi[k], v);
        }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis])
            axis = k;
    for (uint32_t i = 0; i < count; ++i) {
        uint32_t t = b->perm[first + i];
        b->keys[i].key = b->cent[3 * t + axis];
        b->keys[i].index = t;
    }
    sort_keys(b->keys, b->keys + count, count);
    for (uint32_t i = 0; i < count; ++i)
        b->perm[first + i] = b->keys[i].index;
    uint32_t half = count / 2;
    build_node(b, first, half);
    uint32_t right = build_node(b, first + half, count - half);
    b->nodes[idx].right = right;
    return idx;
}

/* A triangle's bounding sphere about its centroid g and its area into
 * s[0..5): g and the area as the build computed them (cent, area), the
 * radius here; kept, as every evaluation that opens the triangle's leaf
 * needs them. */
static void tri_sphere(const double* v, const double g[3], double area, double s[5])
{
    double rad2 = 0.0;
    for (int c = 0; c < 3; ++c) {
        double d[3];
        sub3(v + 3 * c, g, d);
        rad2 = fmax(rad2, dot3(d, d));
    }
    memcpy(s, g, 3 * sizeof(double));
    s[3] = sqrt(rad2);
    s[4] = area;
}

/* >>create / destroy ------------------------------------------------------- */

meso_result meso_lp_field_create(const float* positions, uint32_t nv, const uint32_t* indices, uint32_t nt,
                                 const meso_lp_options* opt, meso_lp_field** out, meso_error* err)
{
    if (!out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: out is NULL");
    *out = NULL;
    if (!positions || !indices)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: positions or indices is NULL");
    if (nv == 0 || nt == 0)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: empty mesh (%u vertices, %u triangles)", nv,
                              nt);
    if (nt > UINT32_MAX / 2)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: %u triangles is too many", nt);
    meso_lp_options o = opt ? *opt : (meso_lp_options){0};
    o.p = o.p == 0.0 ? MESO_LP_DEFAULT_P : o.p;
    o.theta = o.theta == 0.0 ? MESO_LP_DEFAULT_THETA : o.theta;
    o.quad_tol = o.quad_tol == 0.0 ? MESO_LP_DEFAULT_QUAD_TOL : o.quad_tol;
    o.order = o.order == 0 ? 2 : o.order;
    if (!(o.p > 2.0 && o.p <= MESO_LP_MAX_P)) /* p <= 2: the polar radial integral is a log (not implemented) */
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: p = %g is outside (2, 16]", o.p);
    if (!(o.theta > 0.0 && o.theta <= 1.5))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: opening angle theta = %g is outside (0, 1.5]", o.theta);
    if (!(o.near_radius >= 0.0 && isfinite(o.near_radius)))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: near_radius = %g must be finite and >= 0", o.near_radius);
    if (!(o.quad_tol > 0.0 && o.quad_tol <= 0.1))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: quad_tol = %g is outside (0, 0.1]", o.quad_tol);
    if (o.order != 1 && o.order != 2)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: order = %d is not 1 or 2", o.order);
    for (int k = 0; o.region && k < 3; ++k)
        if (!(isfinite(o.region[k]) && isfinite(o.region[3 + k]) && o.region[k] <= o.region[3 + k]))
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: region axis %d is [%g, %g]", k, o.region[k],
                                  o.region[3 + k]);

    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < nv; ++i)
        for (int k = 0; k < 3; ++k) {
            double v = positions[3 * (size_t)i + k];
            if (!isfinite(v))
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                                      "lp field: vertex %u has a non-finite coordinate (%g)", i, v);
            lo[k] = fmin(lo[k], v);
            hi[k] = fmax(hi[k], v);
        }
    for (uint32_t t = 0; t < nt; ++t)
        for (int k = 0; k < 3; ++k)
            if (indices[3 * (size_t)t + k] >= nv)
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                                      "lp field: triangle %u refers to vertex %u, but there are %u vertices", t,
                                      indices[3 * (size_t)t + k], nv);
    double origin[3], diag2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        origin[k] = 0.5 * (lo[k] + hi[k]);
        diag2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    }
    double scale = sqrt(diag2);
    if (!(scale > 0.0))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: the mesh has zero total area (all vertices coincide)");

    meso_lp_field* f = calloc(1, sizeof(*f));
    double* tri = malloc(sizeof(double) * 9 * (size_t)nt);
    double* cent = malloc(sizeof(double) * 3 * (size_t)nt);
    double* area = malloc(sizeof(double) * (size_t)nt);
    uint32_t* perm = malloc(sizeof(uint32_t) * (size_t)nt);
    sort_key* keys = malloc(sizeof(sort_key) * 2 * (size_t)nt);
    lp_node* nodes = malloc(sizeof(lp_node) * 2 * (size_t)nt);
    double* tri_out = malloc(sizeof(double) * 9 * (size_t)nt);
    double* sphere = malloc(sizeof(double) * 5 * (size_t)nt);
    meso_result r = MESO_OK;
    if (!f || !tri || !cent || !area || !perm || !keys || !nodes || !tri_out || !sphere) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "lp field: out of memory (%u triangles)", nt);
        goto fail;
    }
    atomic_init(&f->unsplit_opened, 0);
    double total = 0.0;
    for (uint32_t t = 0; t < nt; ++t) {
        double* v = tri + 9 * (size_t)t;
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                v[3 * c + k] = (positions[3 * (size_t)indices[3 * (size_t)t + c] + k] - origin[k]) / scale;
        double e1[3], e2[3], cr[3];
        sub3(v + 3, v, e1);
        sub3(v + 6, v, e2);
        cross3(e1, e2, cr);
        area[t] = 0.5 * sqrt(dot3(cr, cr));
        total += area[t];
        for (int k = 0; k < 3; ++k)
            cent[3 * t + k] = (v[k] + v[3 + k] + v[6 + k]) / 3.0;
        perm[t] = t;
    }
    if (!(total > 0.0)) {
        r = meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "lp field: the mesh has zero total area (%u degenerate triangles)",
                           nt);
        goto fail;
    }
    build_ctx b = {tri, cent, area, perm, keys, nodes, 0, o.region != NULL, {0, 0, 0}, {0, 0, 0},
                   o.theta * o.theta};
    for (int k = 0; o.region && k < 3; ++k) {
        b.rlo[k] = (o.region[k] - origin[k]) / scale;
        b.rhi[k] = (o.region[3 + k] - origin[k]) / scale;
    }
    o.region = NULL; /* read here only */
    build_node(&b, 0, nt);
    for (uint32_t i = 0; i < nt; ++i) {
        memcpy(tri_out + 9 * (size_t)i, tri + 9 * (size_t)perm[i], 9 * sizeof(double));
        tri_sphere(tri_out + 9 * (size_t)i, cent + 3 * (size_t)perm[i], area[perm[i]], sphere + 5 * (size_t)i);
    }
    f->opt = o;
    memcpy(f->origin, origin, sizeof(origin));
    f->scale = scale;
    f->area = total;
    f->pint = o.p == floor(o.p) ? (int)o.p : 0;
    f->nt = nt;
    f->node_count = b.count;
    f->tri = tri_out;
    f->sphere = sphere;
    f->nodes = nodes;
    tri_out = NULL;
    sphere = NULL;
    nodes = NULL;
    *out = f;
    f = NULL;
fail:
    free(f);
    free(tri);
    free(cent);
    free(area);
    free(perm);
    free(keys);
    free(nodes);
    free(tri_out);
    free(sphere);
    return r;
}

uint64_t meso_lp_field_unsplit_opened(const meso_lp_field* f)
{
    return f ? atomic_load_explicit(&((meso_lp_field*)f)->unsplit_opened, memory_order_relaxed) : 0;
}

void meso_lp_field_destroy(meso_lp_field* f)
{
    if (!f)
        return;
    free(f->tri);
    free(f->sphere);
    free(f->nodes);
    free(f);
}

double meso_lp_field_area(const meso_lp_field* f)
{
    return f ? f->area * f->scale * f->scale : 0.0;
}

meso_lp_options meso_lp_field_options(const meso_lp_field* f)
{
    return f ? f->opt : (meso_lp_options){0};
}

/* >>evaluation -------------------------------------------------------------- */

typedef struct eval_acc {
    double I, J[3];
    int on_surface;
} eval_acc;

static void add_exact(const meso_lp_field* f, const double* v, const double x[3], eval_acc* acc)
{
    double j[3], I;
    if (f->pint == 3) {
        I = meso_lp_triangle_p3(v, v + 3, v + 6, x, j);
    } else {
        quad_ctx q = {x, f->opt.p, f->pint};
        I = quad_triangle(v, v + 3, v + 6, &q, f->opt.quad_tol, j);
    }
    if (isinf(I))
        acc->on_surface = 1;
    acc->I += I;
    for (int k = 0; k < 3; ++k)
        acc->J[k] += j[k];
}

/* Point source of weight w at y. */
static inline void add_point(const meso_lp_field* f, const double x[3], const double y[3], double w, eval_acc* acc)
{
    double R[3];
    sub3(x, y, R);
    double r2 = dot3(R, R);
    const double ir2 = 1.0 / r2, k0 = inv_pow_from_inverse(ir2, f->opt.p, f->pint), k2 = k0 * ir2;
    acc->I += w * k0;
    for (int k = 0; k < 3; ++k)
        acc->J[k] += w * k2 * R[k];
}

static void add_multipole(const meso_lp_field* f, const lp_node* nd, const double R[3], double r2, eval_acc* acc)
{
    double p = f->opt.p;
    const double ir2 = 1.0 / r2, k0 = inv_pow_from_inverse(ir2, p, f->pint), k2 = k0 * ir2;
    acc->I += nd->area * k0;
    for (int k = 0; k < 3; ++k)
        acc->J[k] += nd->area * k2 * R[k];
    if (f->opt.order < 2)
        return;
    /* I_quad = ½ ∇∇(r^−p) : M = ½ (−p r^(−p−2) tr M + p(p+2) r^(−p−4) RᵀMR);
     * J_quad = −(1/p) ∇I_quad (header, >>Barnes–Hut). */
    const double* m = nd->m;
    double MR[3] = {m[0] * R[0] + m[3] * R[1] + m[4] * R[2], m[3] * R[0] + m[1] * R[1] + m[5] * R[2],
                    m[4] * R[0] + m[5] * R[1] + m[2] * R[2]};
    double tr = m[0] + m[1] + m[2], q = dot3(R, MR);
    const double k4 = k2 * ir2, k6 = k4 * ir2;
    acc->I += 0.5 * (-p * k2 * tr + p * (p + 2.0) * k4 * q);
    for (int k = 0; k < 3; ++k)
        acc->J[k] -= 0.5 * (p + 2.0) * (k4 * tr * R[k] + 2.0 * k4 * MR[k] - (p + 4.0) * k6 * q * R[k]);
}

/* Is a cluster of radius rad at squared distance r2 far enough? */
static inline int far_enough(double rad, double r2, double theta, double near_r)
{
    if (!(rad * rad < theta * theta * r2))
        return 0;
    return near_r <= 0.0 || sqrt(r2) - rad > near_r;
}

/* Does a cluster of radius rad at squared distance r2 lie entirely beyond
 * the cut-off (localisation)? */
static inline int beyond(double rad, double r2, double cut_r)
{
    return r2 > (cut_r + rad) * (cut_r + rad);
}

static void add_leaf_triangle(const meso_lp_field* f, uint32_t t, const double x[3], double theta, double near_r,
                              double cut_r, eval_acc* acc, meso_lp_stats* st)
{
    const double* v = f->tri + 9 * (size_t)t;
    const double* s = f->sphere + 5 * (size_t)t;
    double R[3];
    sub3(x, s, R);
    const double r2 = dot3(R, R);
    if (cut_r > 0.0 && beyond(s[3], r2, cut_r))
        return;
    if (!far_enough(s[3], r2, theta, near_r)) {
        add_exact(f, v, x, acc);
        if (st)
            st->exact_triangles++;
        return;
    }
    const double area = s[4];
    if (f->opt.order < 2) {
        add_point(f, x, s, area, acc);
    } else {
        /* Edge-midpoint rule: exact for quadratics, the same order as the
         * nodes' quadrupole expansion. */
        for (int c = 0; c < 3; ++c) {
            const double* p0 = v + 3 * c;
            const double* p1 = v + 3 * ((c + 1) % 3);
            double mid[3] = {0.5 * (p0[0] + p1[0]), 0.5 * (p0[1] + p1[1]), 0.5 * (p0[2] + p1[2])};
            add_point(f, x, mid, area / 3.0, acc);
        }
    }
    if (st)
        st->far_triangles++;
}

static meso_result eval(const meso_lp_field* f, const double xin[3], double theta, double near_radius, double cutoff,
                        double* d, double grad[3], meso_lp_stats* st)
{
    if (!f || !xin || !d)
        return MESO_ERR_INVALID_ARG;
    *d = 0.0;
    if (grad)
        grad[0] = grad[1] = grad[2] = 0.0;
    if (!isfinite(xin[0]) || !isfinite(xin[1]) || !isfinite(xin[2]) || isnan(theta) || isnan(near_radius))
        return MESO_ERR_INVALID_ARG;
    double x[3];
    for (int k = 0; k < 3; ++k)
        x[k] = (xin[k] - f->origin[k]) / f->scale;
    const double near_r = near_radius / f->scale, cut_r = cutoff / f->scale;
    eval_acc acc = {0.0, {0.0, 0.0, 0.0}, 0};
    if (!(theta > 0.0)) {
        for (uint32_t t = 0; t < f->nt; ++t) {
            const double* v = f->tri + 9 * (size_t)t;
            const double* s = f->sphere + 5 * (size_t)t;
            double R[3];
            if (cut_r > 0.0 && (sub3(x, s, R), beyond(s[3], dot3(R, R), cut_r)))
                continue;
            add_exact(f, v, x, &acc);
            if (st)
                st->exact_triangles++;
        }
    } else {
        uint32_t stack[STACK_DEPTH];
        int top = 0;
        stack[top++] = 0;
        while (top > 0) {
            const lp_node* nd = &f->nodes[stack[--top]];
            if (st)
                st->nodes_visited++;
            double R[3];
            sub3(x, nd->c, R);
            double r2 = dot3(R, R);
            if (cut_r > 0.0 && beyond(nd->radius, r2, cut_r)) {
                /* localised: not summed */
            } else if (far_enough(nd->radius, r2, theta, near_r)) {
                add_multipole(f, nd, R, r2, &acc);
                if (st)
                    st->multipoles++;
            } else if (nd->right == 0) {
                if (nd->count > LEAF_SIZE) /* left unsplit for a region (>>regions): not the whole tree's bits */
                    atomic_fetch_add_explicit(&((meso_lp_field*)f)->unsplit_opened, 1, memory_order_relaxed);
                for (uint32_t t = nd->first; t < nd->first + nd->count; ++t)
                    add_leaf_triangle(f, t, x, theta, near_r, cut_r, &acc, st);
            } else {
                /* Second child first on the stack so the first is summed first. */
                stack[top++] = nd->right;
                stack[top++] = (uint32_t)(nd - f->nodes) + 1;
            }
        }
    }
    if (acc.on_surface || !(acc.I > 0.0) || !isfinite(acc.I))
        return MESO_ERR_INVALID_ARG;
    /* d = (I/A)^(−1/p); ∇d = d J / I (header, >>gradient). */
    double ds = f->pint == 3 ? cbrt(f->area / acc.I) : pow(f->area / acc.I, 1.0 / f->opt.p);
    *d = ds * f->scale;
    if (grad)
        for (int k = 0; k < 3; ++k)
            grad[k] = ds * acc.J[k] / acc.I;
    return MESO_OK;
}

meso_result meso_lp_eval_ex(const meso_lp_field* f, const double x[3], double theta, double near_radius, double* d,
                            double grad[3], meso_lp_stats* st)
{
    return eval(f, x, theta, near_radius, 0.0, d, grad, st);
}

meso_result meso_lp_eval_local(const meso_lp_field* f, const double x[3], double theta, double cutoff, double* d,
                               double grad[3], meso_lp_stats* st)
{
    if (!(cutoff > 0.0))
        return MESO_ERR_INVALID_ARG;
    return eval(f, x, theta, 0.0, cutoff, d, grad, st);
}

meso_result meso_lp_eval(const meso_lp_field* f, const double x[3], double* d, double grad[3])
{
    if (!f)
        return MESO_ERR_INVALID_ARG;
    return meso_lp_eval_ex(f, x, f->opt.theta, f->opt.near_radius, d, grad, NULL);
}

meso_result meso_lp_eval_exact(const meso_lp_field* f, const double x[3], double* d, double grad[3])
{
    return meso_lp_eval_ex(f, x, 0.0, 0.0, d, grad, NULL);
}
