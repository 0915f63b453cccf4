/*
 * frustum_reference.c — exact ray casting of conical frusta
 * (frustum_reference.h; relief-mapped-conical-frusta.md §2.5).
 *
 * The ray is not moved into the segment's local frame as the paper does;
 * the same quadratic is formed from the axial/radial split of o − c0 and d,
 * which is the paper's eq. 10 with r(y) = r0 + k y in place of
 * r0 (h' − y)/h'. Roots come from the numerically stable form
 * q = −(b + sign(b)√disc)/2, t = q/a, c/q.
 */
#include "frustum_reference.h"

#include "vec3d.h"

#include <float.h>
#include <math.h>
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

/* y where the cone generator with unit radial direction w meets plane i:
 * n·(c0 + y a + r(y) w) = d, linear in y. Returns 0 when the generator is
 * parallel to the plane. */
static int generator_plane(const meso_ref_frustum* f, const seg_geom* g, int i, const double w[3], double* y)
{
    const double* n = f->plane_n[i];
    double nw = dot3(n, w);
    double den = dot3(n, g->a) + g->k * nw;
    double num = f->plane_d[i] - dot3(n, f->c0) - f->r0 * nw;
    if (fabs(den) < 1e-300)
        return 0;
    *y = num / den;
    return 1;
}

static int inside_planes(const meso_ref_frustum* f, const seg_geom* g, const double p[3], double eps)
{
    (void)g;
    return dot3(f->plane_n[0], p) <= f->plane_d[0] + eps && dot3(f->plane_n[1], p) <= f->plane_d[1] + eps;
}

int meso_ref_frustum_contains(const meso_ref_frustum* f, const double p[3])
{
    seg_geom g;
    seg_setup(f, &g);
    double q[3];
    double y = split(f, &g, p, q);
    double r = f->r0 + g.k * y;
    return r >= 0 && dot3(q, q) <= r * r && inside_planes(f, &g, p, 0.0);
}

static void uv_impl(const meso_ref_frustum* f, const seg_geom* g, const double p[3], double* u, double* v, double sn[3])
{
    double q[3];
    double y = split(f, g, p, q);
    double w[3] = {q[0], q[1], q[2]};
    if (normalize3(w) <= 1e-15 * g->scale) {
        if (dot3(f->frame_x, f->frame_x) > 0.5)
            memcpy(w, f->frame_x, sizeof(w));
        else
            any_perp3(g->a, w);
    }
    double y0 = 0, y1 = g->h;
    int ok0 = generator_plane(f, g, 0, w, &y0);
    int ok1 = generator_plane(f, g, 1, w, &y1);
    if (!ok0)
        y0 = 0;
    if (!ok1)
        y1 = g->h;
    double vv = (y1 != y0) ? (y - y0) / (y1 - y0) : 0.0;
    double z[3];
    cross3(f->frame_x, g->a, z);
    double ang = atan2(dot3(q, f->frame_x), dot3(q, z)) / TAU;
    double uu = ang - f->u_offset + vv * f->twist / TAU;
    uu -= floor(uu);
    if (uu >= 1.0)
        uu = 0.0;
    if (u)
        *u = uu;
    if (v)
        *v = vv;
    if (sn) {
        double nl[3], nu[3];
        for (int i = 0; i < 3; ++i) {
            /* P0 − c0 and P1 − c1 (the generator points on the two planes). */
            nl[i] = y0 * g->a[i] + (f->r0 + g->k * y0) * w[i];
            nu[i] = (y1 - g->h) * g->a[i] + (f->r0 + g->k * y1) * w[i];
        }
        normalize3(nl);
        normalize3(nu);
        for (int i = 0; i < 3; ++i)
            sn[i] = (1 - vv) * nl[i] + vv * nu[i];
        if (normalize3(sn) == 0)
            memcpy(sn, w, sizeof(w));
    }
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
        if (!inside_planes(f, g, p, eps))
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

int meso_ref_frusta_intersect(const meso_ref_frustum* segs, uint32_t seg_count, const meso_ref_ball* balls,
    uint32_t ball_count, const double o[3], const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit)
{
    int found = 0;
    double best = tmax;
    meso_ref_frustum_hit h;
    for (uint32_t s = 0; s < seg_count; ++s) {
        seg_geom g;
        seg_setup(&segs[s], &g);
        double c[3], rad, ts[2];
        if (seg_bound(&segs[s], &g, c, &rad)) {
            int n = ray_sphere(c, rad, o, d, ts);
            if (n < 2 || ts[1] < tmin || ts[0] > best)
                continue;
        }
        if (intersect_impl(&segs[s], &g, o, d, tmin, best, &h)) {
            best = h.t;
            *hit = h;
            hit->index = (int32_t)s;
            found = 1;
        }
    }
    for (uint32_t b = 0; b < ball_count; ++b) {
        double ts[2];
        int n = ray_sphere(balls[b].center, balls[b].radius, o, d, ts);
        for (int j = 0; j < n; ++j) {
            if (ts[j] < tmin || ts[j] > best)
                continue;
            memset(&h, 0, sizeof(h));
            h.t = ts[j];
            for (int i = 0; i < 3; ++i) {
                h.p[i] = o[i] + ts[j] * d[i];
                h.normal[i] = h.p[i] - balls[b].center[i];
            }
            normalize3(h.normal);
            memcpy(h.shading_normal, h.normal, sizeof(h.normal));
            h.index = (int32_t)b;
            h.part = MESO_REF_PART_BALL;
            best = h.t;
            *hit = h;
            found = 1;
            break;
        }
    }
    return found;
}
