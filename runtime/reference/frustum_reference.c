/*
 * frustum_reference.c — exact ray casting of conical frusta and their
 * relief (frustum_reference.h; relief-mapped-conical-frusta.md §2.5, §3).
 *
 * The ray is not moved into the segment's local frame as the paper does;
 * the same quadratic is formed from the axial/radial split of o − c0 and d,
 * which is the paper's eq. 10 with r(y) = r0 + k y in place of
 * r0 (h' − y)/h'. Roots come from the numerically stable form
 * q = −(b + sign(b)√disc)/2, t = q/a, c/q.
 *
 * Sections: >>relief (the search the header derives: step control,
 * crossing exclusion, bisection, normals). One segment at a time; models of
 * many segments and balls, their records, files and rendering are in
 * frusta_model_reference.c.
 */
#include "frustum_reference.h"

#include "frustum_reference_internal.h"
#include "ref_common.h"
#include "vec3d.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define TAU 6.283185307179586

/* Per-segment quantities the queries share. */
typedef struct seg_geom {
    double a[3]; /* unit axis */
    double h;    /* length */
    double k;    /* dr/dy */
    double scale;/* length scale for tolerances */
} seg_geom;

static void seg_setup(const meso_ref_frustum* f, seg_geom* g)
{
    double v[3] = {f->c1[0] - f->c0[0], f->c1[1] - f->c0[1], f->c1[2] - f->c0[2]};
    g->h = normalize3(v);
    memcpy(g->a, v, sizeof(v));
    g->k = g->h > 0 ? (f->r1 - f->r0) / g->h : 0.0;
    g->scale = g->h + f->r0 + f->r1 + 1e-300;
}

/* Axial coordinate y and radial vector q of p. */
static double split(const meso_ref_frustum* f, const seg_geom* g, const double p[3], double q[3])
{
    double w[3] = {p[0] - f->c0[0], p[1] - f->c0[1], p[2] - f->c0[2]};
    double y = dot3(w, g->a);
    for (int i = 0; i < 3; ++i)
        q[i] = w[i] - y * g->a[i];
    return y;
}

/* y where the generator with unit radial direction w of the cone
 * r(y) + delta meets plane i: n·(c0 + y a + (r(y) + delta) w) = d, linear
 * in y. Returns 0 when the generator is parallel to the plane. */
static int generator_plane(const meso_ref_frustum* f, const seg_geom* g, int i, const double w[3], double delta,
    double* y)
{
    const double* n = f->plane_n[i];
    double nw = dot3(n, w);
    double den = dot3(n, g->a) + g->k * nw;
    double num = f->plane_d[i] - dot3(n, f->c0) - (f->r0 + delta) * nw;
    if (fabs(den) < 1e-300)
        return 0;
    *y = num / den;
    return 1;
}

static int inside_planes(const meso_ref_frustum* f, const double p[3], double eps)
{
    return dot3(f->plane_n[0], p) <= f->plane_d[0] + eps && dot3(f->plane_n[1], p) <= f->plane_d[1] + eps;
}

int meso_ref_frustum_contains(const meso_ref_frustum* f, const double p[3])
{
    seg_geom g;
    seg_setup(f, &g);
    double q[3];
    double y = split(f, &g, p, q);
    double r = f->r0 + g.k * y;
    return r >= 0 && dot3(q, q) <= r * r && inside_planes(f, p, 0.0);
}

/* A point in the segment's cylindrical terms, on the cone through it. */
typedef struct cone_pt {
    double y;      /* axial coordinate */
    double rho;    /* |q| */
    double delta;  /* |q| − r(y): the offset of the cone through p */
    double w[3];   /* unit radial direction (frame_x on the axis) */
    double y0, y1; /* where that cone's generator through p meets plane 0 / 1 */
    double u, v;   /* §2.3 */
} cone_pt;

static void cone_param(const meso_ref_frustum* f, const seg_geom* g, const double p[3], cone_pt* c)
{
    double q[3];
    c->y = split(f, g, p, q);
    memcpy(c->w, q, sizeof(q));
    c->rho = normalize3(c->w);
    if (c->rho <= 1e-15 * g->scale) {
        if (dot3(f->frame_x, f->frame_x) > 0.5)
            memcpy(c->w, f->frame_x, sizeof(c->w));
        else
            any_perp3(g->a, c->w);
    }
    c->delta = c->rho - (f->r0 + g->k * c->y);
    c->y0 = 0;
    c->y1 = g->h;
    if (!generator_plane(f, g, 0, c->w, c->delta, &c->y0))
        c->y0 = 0;
    if (!generator_plane(f, g, 1, c->w, c->delta, &c->y1))
        c->y1 = g->h;
    c->v = (c->y1 != c->y0) ? (c->y - c->y0) / (c->y1 - c->y0) : 0.0;
    double z[3];
    cross3(f->frame_x, g->a, z);
    double uu = atan2(dot3(q, f->frame_x), dot3(q, z)) / TAU - f->u_offset + c->v * f->twist / TAU;
    uu -= floor(uu);
    c->u = uu >= 1.0 ? 0.0 : uu;
}

/* Eq. 8 on the cone through the point: N_l = unit(P0 − c0), N_u = unit(P1 − c1).
 * P_e lies on plane e through c_e, so P_e − c_e = ρ_e (w − (n_e·w / n_e·a) a)
 * with ρ_e ≥ 0 the radius there: the direction is taken from that form,
 * which stays exact where ρ_e → 0 (a pointed tip, where P1 − c1 itself is
 * rounding noise) and is eq. 8's limit there. */
static void eq8_normal(const meso_ref_frustum* f, const seg_geom* g, const cone_pt* c, double sn[3])
{
    double nl[3], nu[3];
    const double s0 = dot3(f->plane_n[0], c->w) / dot3(f->plane_n[0], g->a);
    const double s1 = dot3(f->plane_n[1], c->w) / dot3(f->plane_n[1], g->a);
    for (int i = 0; i < 3; ++i) {
        nl[i] = c->w[i] - s0 * g->a[i];
        nu[i] = c->w[i] - s1 * g->a[i];
    }
    normalize3(nl);
    normalize3(nu);
    for (int i = 0; i < 3; ++i)
        sn[i] = (1 - c->v) * nl[i] + c->v * nu[i];
    if (normalize3(sn) == 0)
        memcpy(sn, c->w, sizeof(c->w));
}

static void uv_impl(const meso_ref_frustum* f, const seg_geom* g, const double p[3], double* u, double* v, double sn[3])
{
    cone_pt c;
    cone_param(f, g, p, &c);
    if (u)
        *u = c.u;
    if (v)
        *v = c.v;
    if (sn)
        eq8_normal(f, g, &c, sn);
}

void meso_ref_frustum_uv(const meso_ref_frustum* f, const double p[3], double* u, double* v, double shading_normal[3])
{
    seg_geom g;
    seg_setup(f, &g);
    uv_impl(f, &g, p, u, v, shading_normal);
}

/* Real roots of a t² + b t + c = 0, ascending; returns how many. */
static int solve_quadratic(double a, double b, double c, double t[2])
{
    double s = fabs(a) + fabs(b) + fabs(c);
    if (s == 0)
        return 0;
    if (fabs(a) <= 1e-14 * s) {
        if (b == 0)
            return 0;
        t[0] = -c / b;
        return 1;
    }
    double disc = b * b - 4 * a * c;
    if (disc < 0)
        return 0;
    double sq = sqrt(disc);
    double qq = -0.5 * (b + (b >= 0 ? sq : -sq));
    if (qq == 0) {
        t[0] = t[1] = 0;
        return 2;
    }
    double x0 = qq / a, x1 = c / qq;
    t[0] = fmin(x0, x1);
    t[1] = fmax(x0, x1);
    return 2;
}

static int intersect_impl(const meso_ref_frustum* f, const seg_geom* g, const double o[3], const double d[3], double tmin,
    double tmax, meso_ref_frustum_hit* hit)
{
    double dl = sqrt(dot3(d, d));
    if (!(dl > 0))
        return 0;
    double eps = 1e-12 * g->scale; /* slack of the plane and nappe tests (world units) */
    double best = tmax;
    int found = 0;
    meso_ref_frustum_part part = MESO_REF_PART_LATERAL;

    /* Lateral surface: |q(t)|² = r(y(t))². */
    double qo[3], qd[3];
    double yo = split(f, g, o, qo);
    double yd = dot3(d, g->a);
    for (int i = 0; i < 3; ++i)
        qd[i] = d[i] - yd * g->a[i];
    double ro = f->r0 + g->k * yo;
    double A = dot3(qd, qd) - g->k * g->k * yd * yd;
    double B = 2 * (dot3(qo, qd) - g->k * yd * ro);
    double C = dot3(qo, qo) - ro * ro;
    double ts[2];
    int nt = solve_quadratic(A, B, C, ts);
    for (int j = 0; j < nt; ++j) {
        double t = ts[j];
        if (t < tmin || t > best)
            continue;
        double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        double y = yo + t * yd;
        if (f->r0 + g->k * y < -eps)
            continue; /* mirror nappe */
        if (!inside_planes(f, p, eps))
            continue;
        best = t;
        found = 1;
        part = MESO_REF_PART_LATERAL;
        break; /* roots ascend */
    }
    /* Flat caps. */
    for (int e = 0; e < 2; ++e) {
        if (!f->cap[e])
            continue;
        double nd = dot3(f->plane_n[e], d);
        if (fabs(nd) < 1e-300)
            continue;
        double t = (f->plane_d[e] - dot3(f->plane_n[e], o)) / nd;
        if (t < tmin || t > best)
            continue;
        double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
        double q[3];
        double y = split(f, g, p, q);
        double r = f->r0 + g->k * y;
        if (r < 0 || sqrt(dot3(q, q)) > r + eps)
            continue;
        if (dot3(f->plane_n[1 - e], p) > f->plane_d[1 - e] + eps)
            continue;
        best = t;
        found = 1;
        part = e == 0 ? MESO_REF_PART_CAP0 : MESO_REF_PART_CAP1;
    }
    if (!found)
        return 0;
    memset(hit, 0, sizeof(*hit));
    hit->t = best;
    for (int i = 0; i < 3; ++i)
        hit->p[i] = o[i] + best * d[i];
    hit->part = part;
    if (part == MESO_REF_PART_LATERAL) {
        double q[3];
        double y = split(f, g, hit->p, q);
        double r = f->r0 + g->k * y;
        /* ∇(|q|² − r²)/2 = q − k r a */
        for (int i = 0; i < 3; ++i)
            hit->normal[i] = q[i] - g->k * r * g->a[i];
        if (normalize3(hit->normal) == 0) { /* the apex: face along the axis */
            double s = (f->r1 < f->r0) ? 1.0 : -1.0;
            for (int i = 0; i < 3; ++i)
                hit->normal[i] = s * g->a[i];
        }
        uv_impl(f, g, hit->p, &hit->u, &hit->v, hit->shading_normal);
    } else {
        int e = part == MESO_REF_PART_CAP0 ? 0 : 1;
        memcpy(hit->normal, f->plane_n[e], sizeof(hit->normal));
        memcpy(hit->shading_normal, f->plane_n[e], sizeof(hit->normal));
        uv_impl(f, g, hit->p, &hit->u, NULL, NULL);
        hit->v = (double)e;
    }
    return 1;
}

int meso_ref_frustum_intersect(const meso_ref_frustum* f, const double o[3], const double d[3], double tmin, double tmax,
    meso_ref_frustum_hit* hit)
{
    seg_geom g;
    seg_setup(f, &g);
    return intersect_impl(f, &g, o, d, tmin, tmax, hit);
}

/* A sphere holding the segment's solid, from the extreme axial extents of
 * its two cut curves: along a generator with radial direction w, the plane
 * is met at y = (e − r0 s)/(m + k s), s = n·w, a monotonic function of s
 * on [−|n⊥|, |n⊥|], so the extremes are at the two ends. Returns 0 (no
 * bound, always test) when a denominator changes sign there. */
static int seg_bound(const meso_ref_frustum* f, const seg_geom* g, double c[3], double* rad)
{
    double ylo = DBL_MAX, yhi = -DBL_MAX;
    for (int i = 0; i < 2; ++i) {
        const double* n = f->plane_n[i];
        double m = dot3(n, g->a);
        double np[3] = {n[0] - m * g->a[0], n[1] - m * g->a[1], n[2] - m * g->a[2]};
        double sa = sqrt(dot3(np, np));
        double e = f->plane_d[i] - dot3(n, f->c0);
        double den0 = m + g->k * sa, den1 = m - g->k * sa;
        /* Along each generator, moving towards c1 must enter plane 0's
         * half-space and leave plane 1's: den < 0 at end 0, > 0 at end 1. */
        if (i == 0 ? (den0 >= 0 || den1 >= 0) : (den0 <= 0 || den1 <= 0))
            return 0;
        double ya = (e - f->r0 * sa) / den0, yb = (e + f->r0 * sa) / den1;
        ylo = fmin(ylo, fmin(ya, yb));
        yhi = fmax(yhi, fmax(ya, yb));
    }
    if (!(yhi >= ylo) || !isfinite(ylo) || !isfinite(yhi))
        return 0;
    double rmax = fmax(fmax(f->r0 + g->k * ylo, f->r0 + g->k * yhi), 0.0);
    double ym = 0.5 * (ylo + yhi);
    for (int i = 0; i < 3; ++i)
        c[i] = f->c0[i] + ym * g->a[i];
    *rad = sqrt(0.25 * (yhi - ylo) * (yhi - ylo) + rmax * rmax) * (1 + 1e-9) + 1e-12 * g->scale;
    return 1;
}

static int ray_sphere(const double c[3], double rad, const double o[3], const double d[3], double t[2])
{
    double w[3] = {o[0] - c[0], o[1] - c[1], o[2] - c[2]};
    return solve_quadratic(dot3(d, d), 2 * dot3(w, d), dot3(w, w) - rad * rad, t);
}

/* >>relief ----------------------------------------------------------------- */

#define RELIEF_STEP_DEFAULT 0.125    /* texels and w per sample (frustum_reference.h) */
#define RELIEF_STEP_MAX 0.5          /* keeps a step inside local_lipschitz's neighbourhood */
#define RELIEF_STEP_FLOOR 1e-7       /* world step floor, × (segment size + D) */
#define RELIEF_BISECT_TOL 1e-9       /* bisection width, × (segment size + D) */
#define RELIEF_MAX_SAMPLES (1u << 20) /* per segment and ray */

static int relief_on(const meso_ref_frustum* f, const meso_ref_relief* rl)
{
    return rl && rl->height.kind == 1 && rl->height.values && rl->height.w > 0 && rl->height.h > 0 &&
           f->relief_depth > 0;
}

double meso_ref_relief_height(const meso_ref_texfn* height, double s, double t, double* dhds, double* dhdt)
{
    const double h = meso_ref_texfn_value(height, s, t, 0);
    /* Inside one cell the interpolant is linear in s (and in t), so a
     * difference of a quarter texel that stays in the cell is its exact
     * derivative; the cell's fraction decides the side (axis_wrap's). */
    const double ax[2] = {s, t};
    double* out[2] = {dhds, dhdt};
    for (int k = 0; k < 2; ++k) {
        if (!out[k])
            continue;
        const uint32_t n = height && height->kind == 1 ? (k ? height->h : height->w) : 0;
        if (n == 0 || !isfinite(ax[k])) {
            *out[k] = 0;
            continue;
        }
        const double x = (ax[k] - floor(ax[k])) * n - 0.5, fx = x - floor(x), dl = 0.25 / n;
        const double sgn = fx <= 0.5 ? 1.0 : -1.0;
        const double h2 = k ? meso_ref_texfn_value(height, s, t + sgn * dl, 0)
                            : meso_ref_texfn_value(height, s + sgn * dl, t, 0);
        *out[k] = sgn * (h2 - h) / dl;
    }
    return h;
}

void meso_ref_frustum_relief_coords(const meso_ref_frustum* f, const double p[3], double* s, double* t, double* w)
{
    seg_geom g;
    seg_setup(f, &g);
    cone_pt c;
    cone_param(f, &g, p, &c);
    if (s)
        *s = c.u * f->u_scale;
    if (t)
        *t = f->v_offset + c.v * f->v_scale;
    if (w)
        *w = f->relief_depth > 0 ? c.delta / f->relief_depth : 0.0;
}

/* Interval of the ray o + t d, t in [tmin, tmax], inside the convex solid
 * |q| ≤ r(y) + dr, r(y) + dr ≥ 0, both planes. face[e]: what bounds end e
 * of the interval: 0 the cone, 1 + i plane i, −1 anything else (tmin, tmax,
 * the nappe). Returns 0 when empty. */
static int solid_interval(const meso_ref_frustum* f, const seg_geom* g, double dr, const double o[3], const double d[3],
    double tmin, double tmax, double iv[2], int face[2])
{
    double lo = tmin, hi = tmax;
    face[0] = face[1] = -1;
    for (int e = 0; e < 2; ++e) {
        const double nd = dot3(f->plane_n[e], d), no = dot3(f->plane_n[e], o) - f->plane_d[e];
        if (fabs(nd) < 1e-300) {
            if (no > 0)
                return 0;
            continue;
        }
        const double tc = -no / nd;
        if (nd > 0 && tc < hi) {
            hi = tc;
            face[1] = 1 + e;
        } else if (nd < 0 && tc > lo) {
            lo = tc;
            face[0] = 1 + e;
        }
    }
    double qo[3], qd[3];
    const double yo = split(f, g, o, qo), yd = dot3(d, g->a);
    for (int i = 0; i < 3; ++i)
        qd[i] = d[i] - yd * g->a[i];
    const double ro = f->r0 + dr + g->k * yo, kd = g->k * yd;
    /* nappe: ro + kd t ≥ 0 */
    if (kd == 0) {
        if (ro < 0)
            return 0;
    } else if (kd > 0) {
        if (-ro / kd > lo) {
            lo = -ro / kd;
            face[0] = -1;
        }
    } else if (-ro / kd < hi) {
        hi = -ro / kd;
        face[1] = -1;
    }
    /* cone: A t² + B t + C ≤ 0 */
    const double A = dot3(qd, qd) - kd * kd, B = 2 * (dot3(qo, qd) - kd * ro), C = dot3(qo, qo) - ro * ro;
    double ts[2];
    const int nr = solve_quadratic(A, B, C, ts);
    if (nr == 0) {
        if (C > 0)
            return 0;
    } else if (nr == 1) {
        if (B > 0 && ts[0] < hi) {
            hi = ts[0];
            face[1] = 0;
        } else if (B < 0 && ts[0] > lo) {
            lo = ts[0];
            face[0] = 0;
        }
    } else if (A > 0) {
        if (ts[0] > lo) {
            lo = ts[0];
            face[0] = 0;
        }
        if (ts[1] < hi) {
            hi = ts[1];
            face[1] = 0;
        }
    } else {
        /* Outside the roots: (−∞, t0] or [t1, ∞). The nappe already keeps
         * one of the two; the other piece is empty up to rounding. */
        const double len0 = fmin(hi, ts[0]) - lo, len1 = hi - fmax(lo, ts[1]);
        if (len0 >= len1) {
            if (ts[0] < hi) {
                hi = ts[0];
                face[1] = 0;
            }
        } else if (ts[1] > lo) {
            lo = ts[1];
            face[0] = 0;
        }
    }
    if (!(lo <= hi))
        return 0;
    iv[0] = lo;
    iv[1] = hi;
    return 1;
}

/* One sample of the march: relief coordinates, the height there and
 * g = w − h (solid: g ≤ 0). */
typedef struct rsample {
    double t, u, s, tt, w, h, g;
} rsample;

typedef struct relief_ray {
    const meso_ref_frustum* f;
    const seg_geom* geo;
    const meso_ref_texfn* hf;
    const double *o, *d;
    double qa, qb, qc; /* |q(t)|² = qa t² + 2 qb t + qc */
    double ro, kd;     /* r(y(t)) = ro + kd t */
    double tol;        /* bisection width (ray parameter) */
    uint32_t samples;
} relief_ray;

static void relief_ray_init(relief_ray* rr, const meso_ref_frustum* f, const seg_geom* g, const meso_ref_texfn* hf,
    const double o[3], const double d[3], double tol)
{
    double qo[3], qd[3];
    const double yo = split(f, g, o, qo), yd = dot3(d, g->a);
    for (int i = 0; i < 3; ++i)
        qd[i] = d[i] - yd * g->a[i];
    *rr = (relief_ray){f, g, hf, o, d, dot3(qd, qd), dot3(qo, qd), dot3(qo, qo), f->r0 + g->k * yo, g->k * yd, tol, 0};
}

static void relief_eval(relief_ray* rr, double t, rsample* s)
{
    const meso_ref_frustum* f = rr->f;
    const double p[3] = {rr->o[0] + t * rr->d[0], rr->o[1] + t * rr->d[1], rr->o[2] + t * rr->d[2]};
    cone_pt c;
    cone_param(f, rr->geo, p, &c);
    s->t = t;
    s->u = c.u;
    s->s = c.u * f->u_scale;
    s->tt = f->v_offset + c.v * f->v_scale;
    s->w = c.delta / f->relief_depth;
    s->h = meso_ref_texfn_value(rr->hf, s->s, s->tt, 0);
    s->g = s->w - s->h;
    rr->samples++;
}

/* Texel-space (L1) distance between two samples: s (the u difference taken
 * the short way round, times u_scale) and t, in texels. */
static double texel_dist(const relief_ray* rr, const rsample* a, const rsample* b)
{
    double du = b->u - a->u;
    du -= floor(du + 0.5);
    return fabs(du * rr->f->u_scale) * rr->hf->w + fabs(b->tt - a->tt) * rr->hf->h;
}

/* Largest move between two samples in the step bound's units (texels of s,
 * texels of t, w). */
static double sample_move(const relief_ray* rr, const rsample* a, const rsample* b)
{
    double du = b->u - a->u;
    du -= floor(du + 0.5);
    const double ms = fabs(du * rr->f->u_scale) * rr->hf->w, mt = fabs(b->tt - a->tt) * rr->hf->h;
    return fmax(fmax(ms, mt), fabs(b->w - a->w));
}

/* The bilinear interpolant's Lipschitz constant (per texel, L1) around a
 * sample: the largest difference of adjacent texels in the 4 × 4 texels
 * whose cells hold every point within one texel of it. */
static double local_lipschitz(const meso_ref_texfn* hf, const rsample* a)
{
    const double x = (a->s - floor(a->s)) * hf->w - 0.5, y = (a->tt - floor(a->tt)) * hf->h - 0.5;
    const long W = (long)hf->w, H = (long)hf->h, i0 = (long)floor(x) - 1, j0 = (long)floor(y) - 1;
    double g = 0;
    for (long j = j0; j < j0 + 4; ++j)
        for (long i = i0; i < i0 + 4; ++i) {
            const long ii = ((i % W) + W) % W, jj = ((j % H) + H) % H;
            const long i1 = (ii + 1) % W, j1 = (jj + 1) % H;
            const double v = hf->values[jj * W + ii];
            if (i < i0 + 3)
                g = fmax(g, fabs(hf->values[jj * W + i1] - v));
            if (j < j0 + 3)
                g = fmax(g, fabs(hf->values[j1 * W + ii] - v));
        }
    return g;
}

static double w_at(const relief_ray* rr, double t)
{
    return (sqrt(fmax(0.0, (rr->qa * t + 2 * rr->qb) * t + rr->qc)) - (rr->ro + rr->kd * t)) / rr->f->relief_depth;
}

/* 1 when g cannot change sign between samples a and b (same sign): g ≥
 * min w − max h for non-solid ends, ≤ max w − min h for solid ones. w is
 * convex along the ray (|q(t)| is a norm of an affine map, r(y(t)) affine),
 * so its maximum is at an end and its minimum at the clamped stationary
 * point of |q(t)| − kd t: with τ = t + qb/qa, m² = qc − qb²/qa,
 * τ* = kd m / √(qa (qa − kd²)) when qa > kd² (else monotone). h on the path
 * (≤ 2× the chord in texels, the step keeping it short) is within
 * G · chord of the ends' mean, G = local_lipschitz. */
static int no_crossing(const relief_ray* rr, const rsample* a, const rsample* b)
{
    const double G = local_lipschitz(rr->hf, a), ell = texel_dist(rr, a, b);
    const double hmid = 0.5 * (a->h + b->h);
    if (a->g > 0) {
        double wmin = fmin(a->w, b->w);
        if (rr->qa > rr->kd * rr->kd) {
            const double m = sqrt(fmax(0.0, rr->qc - rr->qb * rr->qb / rr->qa));
            const double ts = rr->kd * m / sqrt(rr->qa * (rr->qa - rr->kd * rr->kd)) - rr->qb / rr->qa;
            if (ts > a->t && ts < b->t)
                wmin = fmin(wmin, w_at(rr, ts));
        }
        return wmin - (hmid + G * ell) > 0;
    }
    return fmax(a->w, b->w) - (hmid - G * ell) <= 0;
}

/* The first sign change of g in (a, b], a evaluated: 1 and its bracket
 * [lo, hi] of width ≤ tol, or 0. Halves are searched left first, each
 * skipped when no_crossing proves it free. */
static int first_crossing(relief_ray* rr, const rsample* a, const rsample* b, double* lo, double* hi)
{
    const int sa = a->g <= 0, sb = b->g <= 0;
    if (b->t - a->t <= rr->tol || rr->samples >= RELIEF_MAX_SAMPLES) {
        if (sa == sb)
            return 0;
        *lo = a->t;
        *hi = b->t;
        return 1;
    }
    if (sa == sb && no_crossing(rr, a, b))
        return 0;
    rsample m;
    relief_eval(rr, 0.5 * (a->t + b->t), &m);
    return first_crossing(rr, a, &m, lo, hi) || first_crossing(rr, &m, b, lo, hi);
}

/* Fills a relief hit at t: lateral (the relief surface w = h) or a cap. */
static void relief_hit(const relief_ray* rr, double t, meso_ref_frustum_part part, meso_ref_frustum_hit* hit)
{
    const meso_ref_frustum* f = rr->f;
    const seg_geom* g = rr->geo;
    const double D = f->relief_depth;
    memset(hit, 0, sizeof(*hit));
    hit->t = t;
    for (int i = 0; i < 3; ++i)
        hit->p[i] = rr->o[i] + t * rr->d[i];
    hit->part = part;
    hit->relief = 1;
    cone_pt c;
    cone_param(f, g, hit->p, &c);
    hit->u = c.u;
    hit->v = c.v;
    hit->w = c.delta / D;
    hit->tex[0] = c.u * f->u_scale;
    hit->tex[1] = f->v_offset + c.v * f->v_scale;
    if (part != MESO_REF_PART_LATERAL) {
        const int e = part == MESO_REF_PART_CAP0 ? 0 : 1;
        memcpy(hit->normal, f->plane_n[e], sizeof(hit->normal));
        memcpy(hit->shading_normal, f->plane_n[e], sizeof(hit->normal));
        hit->v = (double)e;
        return;
    }
    double hs, ht;
    meso_ref_relief_height(rr->hf, hit->tex[0], hit->tex[1], &hs, &ht);
    /* ∇v by central differences (v is smooth off the axis). */
    double gv[3];
    const double del = 1e-6 * (g->scale + D);
    for (int i = 0; i < 3; ++i) {
        double pa[3], pb[3];
        memcpy(pa, hit->p, sizeof(pa));
        memcpy(pb, hit->p, sizeof(pb));
        pa[i] += del;
        pb[i] -= del;
        cone_pt ca, cb;
        cone_param(f, g, pa, &ca);
        cone_param(f, g, pb, &cb);
        gv[i] = (ca.v - cb.v) / (2 * del);
    }
    double tu[3];
    cross3(g->a, c.w, tu); /* direction of increasing u */
    const double rho = c.rho > 1e-300 ? c.rho : 1e-300;
    for (int i = 0; i < 3; ++i) {
        const double gw = (c.w[i] - g->k * g->a[i]) / D;
        const double gu = tu[i] / (TAU * rho) + f->twist / TAU * gv[i];
        hit->normal[i] = gw - f->u_scale * hs * gu - f->v_scale * ht * gv[i];
    }
    if (normalize3(hit->normal) == 0)
        memcpy(hit->normal, c.w, sizeof(c.w));
    /* FORMAT.md's relief shading normal. */
    double n8[3];
    eq8_normal(f, g, &c, n8);
    const double sk = sqrt(1 + g->k * g->k), dy = c.y1 - c.y0;
    const double lu = TAU * rho, lv = fabs(dy) * sk;
    for (int i = 0; i < 3; ++i) {
        const double tv = (dy >= 0 ? 1.0 : -1.0) * (g->a[i] + g->k * c.w[i]) / sk;
        /* ∇u = T_u/L_u + (twist/2π) ∇v: ∂h/∂s also tilts along T_v. */
        const double gv_share = ht * f->v_scale + hs * f->u_scale * f->twist / TAU;
        hit->shading_normal[i] = n8[i] - D * (hs * f->u_scale * tu[i] / lu + (lv > 0 ? gv_share * tv / lv : 0));
    }
    if (normalize3(hit->shading_normal) == 0)
        memcpy(hit->shading_normal, hit->normal, sizeof(hit->normal));
}

/* The relief search of frustum_reference.h for one segment. */
static int relief_intersect(const meso_ref_frustum* f, const seg_geom* g, const meso_ref_relief* rl, const double o[3],
    const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit, uint32_t* samples)
{
    const double D = f->relief_depth, dl = sqrt(dot3(d, d));
    double iv[2], in[2];
    int face[2], inface[2];
    if (!(dl > 0) || !solid_interval(f, g, D, o, d, tmin, tmax, iv, face))
        return 0;
    const int has_in = solid_interval(f, g, 0.0, o, d, iv[0], iv[1], in, inface);
    const double size = g->scale + D;
    const double step = rl->step > 0 ? fmin(rl->step, RELIEF_STEP_MAX) : RELIEF_STEP_DEFAULT;
    const double dt_min = RELIEF_STEP_FLOOR * size / dl;
    relief_ray rr;
    relief_ray_init(&rr, f, g, &rl->height, o, d, RELIEF_BISECT_TOL * size / dl);
    rsample a, b;
    relief_eval(&rr, iv[0], &a);
    int found = 0;
    double th = iv[0];
    meso_ref_frustum_part part = MESO_REF_PART_LATERAL;
    if (a.g <= 0 && face[0] == 0) {
        found = 1; /* entering through the outer cone where h = 1 */
    } else if (a.g <= 0 && face[0] >= 1) {
        found = 1; /* an end face of the relief solid, capped or not (frustum_reference.h) */
        part = face[0] == 1 ? MESO_REF_PART_CAP0 : MESO_REF_PART_CAP1;
    }
    double dt = iv[1] - iv[0];
    while (!found && a.t < iv[1]) {
        if (rr.samples >= RELIEF_MAX_SAMPLES)
            break;
        double tn = fmin(a.t + fmax(dt, dt_min), iv[1]);
        int jump = 0;
        if (has_in && a.t < in[0] && tn > in[0])
            tn = in[0]; /* the core's entry is always a sample */
        else if (has_in && a.t >= in[0] && a.t < in[1]) {
            tn = in[1]; /* solid throughout the core: no crossing inside */
            jump = 1;
        }
        relief_eval(&rr, tn, &b);
        if (has_in && (tn == in[0] || tn == in[1]))
            b.g = fmin(b.g, 0.0); /* on the core: solid, whatever w's rounding says */
        const double mv = sample_move(&rr, &a, &b);
        if (!jump && mv > step && tn - a.t > dt_min) {
            dt = 0.5 * (tn - a.t);
            continue;
        }
        double lo, hi;
        if (!jump && first_crossing(&rr, &a, &b, &lo, &hi)) {
            th = 0.5 * (lo + hi);
            found = 1;
            break;
        }
        if (!jump)
            dt = mv < 0.5 * step ? 2 * (tn - a.t) : tn - a.t;
        a = b;
    }
    if (rr.samples >= RELIEF_MAX_SAMPLES) {
        *samples = UINT32_MAX;
        return 0;
    }
    if (!found && a.g <= 0) {
        /* Solid up to the exit: the top cone where h = 1, or a cap. */
        th = iv[1];
        if (face[1] == 0)
            found = 1;
        else if (face[1] >= 1) {
            found = 1;
            part = face[1] == 1 ? MESO_REF_PART_CAP0 : MESO_REF_PART_CAP1;
        }
    }
    if (*samples != UINT32_MAX)
        *samples += rr.samples;
    if (!found)
        return 0;
    relief_hit(&rr, th, part, hit);
    return 1;
}

int meso_ref_frustum_intersect_relief(const meso_ref_frustum* f, const meso_ref_relief* relief, const double o[3],
    const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit)
{
    seg_geom g;
    seg_setup(f, &g);
    if (!relief_on(f, relief))
        return intersect_impl(f, &g, o, d, tmin, tmax, hit);
    uint32_t samples = 0;
    meso_ref_frustum_hit h;
    const int got = relief_intersect(f, &g, relief, o, d, tmin, tmax, &h, &samples);
    if (got)
        *hit = h;
    hit->steps = samples;
    return got;
}

/* >>for the model (frustum_reference_internal.h) --------------------------- */

int mesoi_ref_segment_bound(const meso_ref_frustum* f, const meso_ref_relief* relief, double c[3], double* rad)
{
    meso_ref_frustum outer = *f;
    if (relief_on(&outer, relief)) {
        outer.r0 += outer.relief_depth;
        outer.r1 += outer.relief_depth;
    }
    seg_geom go;
    seg_setup(&outer, &go);
    return seg_bound(&outer, &go, c, rad);
}

int mesoi_ref_segment_intersect(const meso_ref_frustum* f, const meso_ref_relief* relief, const double o[3],
    const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit, uint32_t* samples)
{
    seg_geom g;
    seg_setup(f, &g);
    return relief_on(f, relief) ? relief_intersect(f, &g, relief, o, d, tmin, tmax, hit, samples)
                                : intersect_impl(f, &g, o, d, tmin, tmax, hit);
}

int mesoi_ref_ray_sphere(const double c[3], double rad, const double o[3], const double d[3], double t[2])
{
    return ray_sphere(c, rad, o, d, t);
}
