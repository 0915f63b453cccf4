/*
 * test_frustum_reference.c — the exact ray–frustum intersection
 * (runtime/reference/frustum_reference.c) against brute force: rays are
 * marched in world space with a fine step, point-in-solid (inside the cone,
 * on its nappe, between both planes) brackets the first entry, and
 * bisection on the same predicate narrows it to 1e-12; the analytic t must
 * agree. Random frusta: oblique planes (up to 30°), cylinders, zero-radius
 * tips and radius jumps (radius far larger than the length).
 *
 * Relief (§3, FORMAT.md §7.2 kind 4), each against an answer computed
 * without the reference's search:
 *  - a constant height h is the plain cone of radius r + h·D (analytic);
 *  - a cylinder seen side-on with a height map stepping along t, and hit by
 *    radial rays with one stepping along s: the hit is the cylinder of
 *    radius R + D·h at the ray's (s, t), h the bilinear value (closed form);
 *  - v along the generator of the cone through p: the generator line is
 *    sampled and bisected against both planes, v = |P − P0| / |P1 − P0|
 *    (eq. 7 taken literally);
 *  - the relief normal against the cross product of neighbouring hits
 *    (finite differences of the rendered surface), and the shading normal
 *    equal to it where eq. 8 is exact (cylinder, perpendicular cuts);
 *  - random height fields: a uniform world-space march 64× finer than the
 *    step bound, bisected on point-in-solid, finds the same first hit.
 */
#include <string.h>

#include "frustum_reference.h"
#include "test_util.h"

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void normalize3(double v[3])
{
    double l = sqrt(dot3(v, v));
    for (int i = 0; i < 3; ++i)
        v[i] /= l;
}

/* A unit vector perpendicular to the unit vector a. */
static void any_perp(const double a[3], double o[3])
{
    double e[3] = {fabs(a[0]) < 0.6 ? 1.0 : 0.0, fabs(a[0]) < 0.6 ? 0.0 : 1.0, 0};
    const double m = dot3(e, a);
    for (int i = 0; i < 3; ++i)
        o[i] = e[i] - m * a[i];
    normalize3(o);
}

static void rand_unit(uint64_t* rng, double v[3])
{
    do {
        for (int i = 0; i < 3; ++i)
            v[i] = test_rng_uniform(rng, -1, 1);
    } while (dot3(v, v) > 1 || dot3(v, v) < 1e-4);
    normalize3(v);
}

/* Plane through p with outward normal: `dir` tilted by up to `tilt` rad. */
static void tilted_plane(uint64_t* rng, const double dir[3], const double p[3], double tilt, double n[3], double* d)
{
    double r[3];
    rand_unit(rng, r);
    double m = dot3(r, dir);
    double perp[3] = {r[0] - m * dir[0], r[1] - m * dir[1], r[2] - m * dir[2]};
    normalize3(perp);
    double ang = test_rng_uniform(rng, 0, tilt);
    for (int i = 0; i < 3; ++i)
        n[i] = cos(ang) * dir[i] + sin(ang) * perp[i];
    *d = dot3(n, p);
}

static void random_frustum(uint64_t* rng, int kind, meso_ref_frustum* f)
{
    memset(f, 0, sizeof(*f));
    double a[3];
    rand_unit(rng, a);
    double h = test_rng_uniform(rng, 0.3, 2.0);
    for (int i = 0; i < 3; ++i) {
        f->c0[i] = test_rng_uniform(rng, -1, 1);
        f->c1[i] = f->c0[i] + h * a[i];
    }
    f->r0 = test_rng_uniform(rng, 0.05, 0.8);
    f->r1 = test_rng_uniform(rng, 0.05, 0.8);
    double tilt = 0.5;
    switch (kind) {
    case 0: break;                                   /* general */
    case 1: f->r1 = f->r0; break;                    /* cylinder */
    case 2: f->r1 = 0; tilt = 0; break;              /* pointed tip, perpendicular plane */
    case 3: f->r0 = 0; tilt = 0; break;              /* tip at c0 */
    case 4: h *= 0.2; f->r1 = 8 * f->r0 + 0.5;       /* radius jump */
        for (int i = 0; i < 3; ++i)
            f->c1[i] = f->c0[i] + h * a[i];
        tilt = 0.15;
        break;
    default: break;
    }
    double na[3] = {-a[0], -a[1], -a[2]};
    tilted_plane(rng, na, f->c0, tilt, f->plane_n[0], &f->plane_d[0]);
    tilted_plane(rng, a, f->c1, tilt, f->plane_n[1], &f->plane_d[1]);
    f->cap[0] = f->cap[1] = 1;
    double e[3] = {1, 0, 0};
    if (fabs(a[0]) > 0.9) {
        e[0] = 0;
        e[1] = 1;
    }
    double m = dot3(e, a);
    for (int i = 0; i < 3; ++i)
        f->frame_x[i] = e[i] - m * a[i];
    normalize3(f->frame_x);
    f->u_offset = test_rng_uniform(rng, 0, 1);
    f->twist = test_rng_uniform(rng, -1, 1);
}

/* 1 when every generator meets plane 0 and then plane 1, both on the
 * cone's own nappe (512 generators): the paper's frustum; otherwise the
 * solid is still convex and the t checks hold, but v is not in [0, 1]. */
static int valid_cut(const meso_ref_frustum* f)
{
    double a[3] = {f->c1[0] - f->c0[0], f->c1[1] - f->c0[1], f->c1[2] - f->c0[2]};
    double h = sqrt(dot3(a, a));
    normalize3(a);
    double k = (f->r1 - f->r0) / h, x[3], z[3];
    memcpy(x, f->frame_x, sizeof(x));
    z[0] = x[1] * a[2] - x[2] * a[1];
    z[1] = x[2] * a[0] - x[0] * a[2];
    z[2] = x[0] * a[1] - x[1] * a[0];
    for (int j = 0; j < 512; ++j) {
        double phi = 6.283185307179586 * j / 512, w[3], y[2];
        for (int i = 0; i < 3; ++i)
            w[i] = sin(phi) * x[i] + cos(phi) * z[i];
        for (int e = 0; e < 2; ++e) {
            double nw = dot3(f->plane_n[e], w), den = dot3(f->plane_n[e], a) + k * nw;
            if ((e == 0 && den >= 0) || (e == 1 && den <= 0))
                return 0;
            y[e] = (f->plane_d[e] - dot3(f->plane_n[e], f->c0) - f->r0 * nw) / den;
            if (f->r0 + k * y[e] < 0)
                return 0;
        }
        if (y[0] >= y[1])
            return 0;
    }
    return 1;
}

static void at(const double o[3], const double d[3], double t, double p[3])
{
    for (int i = 0; i < 3; ++i)
        p[i] = o[i] + t * d[i];
}

static void test_brute_force(void)
{
    uint64_t rng = 0x1234567ULL;
    const int frusta = 150, rays = 40, steps = 6000;
    uint32_t hits = 0, misses = 0, grazing = 0, checked = 0, invalid = 0;
    double worst = 0;
    for (int fi = 0; fi < frusta; ++fi) {
        meso_ref_frustum f;
        random_frustum(&rng, fi % 5, &f);
        int valid = valid_cut(&f);
        invalid += !valid;
        double ctr[3], size = 0;
        for (int i = 0; i < 3; ++i)
            ctr[i] = 0.5 * (f.c0[i] + f.c1[i]);
        double dc[3] = {f.c1[0] - f.c0[0], f.c1[1] - f.c0[1], f.c1[2] - f.c0[2]};
        size = sqrt(dot3(dc, dc)) + f.r0 + f.r1;
        double R = 3 * size;
        for (int ri = 0; ri < rays; ++ri) {
            double o[3], d[3], dir[3], tgt[3];
            rand_unit(&rng, dir);
            for (int i = 0; i < 3; ++i) {
                o[i] = ctr[i] + R * dir[i];
                tgt[i] = ctr[i] + test_rng_uniform(&rng, -0.45, 0.45) * size;
                d[i] = tgt[i] - o[i];
            }
            normalize3(d);
            if (meso_ref_frustum_contains(&f, o))
                continue; /* an unbounded solid (very oblique cut): start outside only */
            double tmax = 2 * R, dt = tmax / steps;
            double tin = -1;
            for (int s = 1; s <= steps; ++s) {
                double p[3];
                at(o, d, s * dt, p);
                if (meso_ref_frustum_contains(&f, p)) {
                    double lo = (s - 1) * dt, hi = s * dt;
                    for (int b = 0; b < 60; ++b) {
                        double mid = 0.5 * (lo + hi);
                        at(o, d, mid, p);
                        if (meso_ref_frustum_contains(&f, p))
                            hi = mid;
                        else
                            lo = mid;
                    }
                    tin = hi;
                    break;
                }
            }
            meso_ref_frustum_hit h;
            int got = meso_ref_frustum_intersect(&f, o, d, 0, tmax, &h);
            ++checked;
            if (tin < 0) {
                if (got) {
                    /* A sliver thinner than the march step: the hit must be
                     * on the solid's boundary. */
                    ++grazing;
                    assert(h.t >= 0 && h.t <= tmax);
                } else
                    ++misses;
                continue;
            }
            if (!got) {
                fprintf(stderr, "frustum %d ray %d: march enters at t = %.9g, caster misses\n", fi, ri, tin);
                assert(got);
            }
            ++hits;
            double err = fabs(h.t - tin) / size;
            worst = fmax(worst, err);
            if (err > 1e-8)
                fprintf(stderr, "frustum %d (kind %d) ray %d: t %.12g vs march %.12g part %d\n", fi, fi % 5, ri, h.t, tin,
                    (int)h.part);
            assert(err <= 1e-8);
            /* The normal points out: a little along it is outside, a little
             * against it inside (away from the rims). */
            double pin[3], pout[3], eps = 1e-6 * size;
            for (int i = 0; i < 3; ++i) {
                pout[i] = h.p[i] + eps * h.normal[i];
                pin[i] = h.p[i] - eps * h.normal[i];
            }
            assert(fabs(dot3(h.normal, h.normal) - 1) < 1e-12);
            assert(dot3(h.normal, d) <= 1e-9); /* entering from outside */
            int rim = !meso_ref_frustum_contains(&f, pin);
            if (!rim)
                assert(!meso_ref_frustum_contains(&f, pout));
            assert(h.u >= 0 && h.u < 1);
            if (valid)
                assert(h.v >= -1e-9 && h.v <= 1 + 1e-9);
        }
    }
    fprintf(stderr,
        "    %d frusta (%u with a plane reaching past the apex or caps crossing), %u rays: %u hits (worst |dt|/size "
        "%.2e), %u misses, %u thinner than the march step\n",
        frusta, invalid, checked, hits, worst, misses, grazing);
    assert(hits > checked / 4 && misses > checked / 10);
    assert(grazing * 100 <= checked);
}

/* Analytic answers: a cylinder along z hit head-on and from the side, a
 * cone's tip, the mirror nappe rejected, (u, v) and the twist. */
static void test_closed_form(void)
{
    meso_ref_frustum f;
    memset(&f, 0, sizeof(f));
    f.c1[2] = 2;
    f.r0 = f.r1 = 0.5;
    f.plane_n[0][2] = -1;
    f.plane_d[0] = 0;
    f.plane_n[1][2] = 1;
    f.plane_d[1] = 2;
    f.frame_x[0] = 1;
    meso_ref_frustum_hit h;
    double o[3] = {-3, 0, 1}, d[3] = {1, 0, 0};
    assert(meso_ref_frustum_intersect(&f, o, d, 0, 100, &h));
    assert(fabs(h.t - 2.5) < 1e-12 && h.part == MESO_REF_PART_LATERAL);
    assert(fabs(h.normal[0] + 1) < 1e-12 && fabs(h.v - 0.5) < 1e-12);
    /* frame x = (1,0,0), z = x × a = (1,0,0)×(0,0,1) = (0,−1,0): the point
     * (−0.5, 0, 1) has q·x = −0.5, q·z = 0 → atan2(−0.5, 0) = −π/2 → u = 0.75. */
    assert(fabs(h.u - 0.75) < 1e-12);
    /* open ends: along the axis the ray passes through (no caps) */
    double o2[3] = {0, 0, -5}, d2[3] = {0, 0, 1};
    assert(!meso_ref_frustum_intersect(&f, o2, d2, 0, 100, &h));
    f.cap[0] = 1;
    assert(meso_ref_frustum_intersect(&f, o2, d2, 0, 100, &h) && fabs(h.t - 5) < 1e-12 && h.part == MESO_REF_PART_CAP0);
    assert(h.v == 0 && fabs(h.normal[2] + 1) < 1e-12);
    /* a ray starting inside leaves through the wall */
    double o3[3] = {0, 0, 1};
    assert(meso_ref_frustum_intersect(&f, o3, d, 0, 100, &h) && fabs(h.t - 0.5) < 1e-12);
    /* a cone with its tip at c1: the mirror nappe beyond the tip is not hit */
    f.r1 = 0;
    f.cap[0] = 0;
    double o4[3] = {-3, 0, 3}, o5[3] = {-3, 0, 1};
    assert(!meso_ref_frustum_intersect(&f, o4, d, 0, 100, &h));
    f.plane_d[1] = 5; /* even when the plane lets it through */
    assert(!meso_ref_frustum_intersect(&f, o4, d, 0, 100, &h));
    assert(meso_ref_frustum_intersect(&f, o5, d, 0, 100, &h) && fabs(h.t - 2.75) < 1e-12);
    /* slanted normal of the cone: (cos, 0, sin) with tan = 0.5/2 */
    double s = 0.25 / sqrt(1 + 0.0625);
    assert(fabs(h.normal[2] - s) < 1e-12);
    /* twist adds v·θ/2π to u */
    f.plane_d[1] = 2;
    f.twist = 1.0;
    double u0 = h.u;
    assert(meso_ref_frustum_intersect(&f, o5, d, 0, 100, &h));
    double du = h.u - u0;
    du -= floor(du);
    assert(fabs(du - 0.5 / 6.283185307179586) < 1e-12);
}

/* The model loop: nearest over segments and balls, bounding spheres never
 * rejecting a true hit. */
static void test_model_loop(void)
{
    uint64_t rng = 0xabcdefULL;
    meso_ref_frustum segs[6];
    meso_ref_ball balls[2] = {{{0.3, 0.2, 0.1}, 0.4}, {{-0.5, 0, 0.6}, 0.3}};
    for (int i = 0; i < 6; ++i)
        random_frustum(&rng, i % 5, &segs[i]);
    for (int ri = 0; ri < 3000; ++ri) {
        double o[3], d[3];
        rand_unit(&rng, o);
        for (int i = 0; i < 3; ++i)
            o[i] *= 8;
        rand_unit(&rng, d);
        for (int i = 0; i < 3; ++i)
            d[i] = -o[i] / 8 + 0.3 * d[i];
        meso_ref_frustum_hit h, hb;
        int got = meso_ref_frusta_intersect(segs, 6, balls, 2, o, d, 0, 1e9, &h);
        double best = 1e9;
        int any = 0;
        for (int s = 0; s < 6; ++s)
            if (meso_ref_frustum_intersect(&segs[s], o, d, 0, 1e9, &hb) && hb.t < best) {
                best = hb.t;
                any = 1;
            }
        for (int b = 0; b < 2; ++b) {
            double w[3] = {o[0] - balls[b].center[0], o[1] - balls[b].center[1], o[2] - balls[b].center[2]};
            double A = dot3(d, d), B = 2 * dot3(w, d), C = dot3(w, w) - balls[b].radius * balls[b].radius;
            double disc = B * B - 4 * A * C;
            if (disc >= 0) {
                double t = (-B - sqrt(disc)) / (2 * A);
                if (t >= 0 && t < best) {
                    best = t;
                    any = 1;
                }
            }
        }
        assert(got == any);
        if (got)
            assert(fabs(h.t - best) <= 1e-12 * (1 + best));
    }
}

/* >>relief ----------------------------------------------------------------- */

#define TAU 6.283185307179586

/* A W × H height field in the order meso_ref_texfn reads it (x fastest). */
static meso_ref_relief make_relief(float* vals, uint32_t w, uint32_t h)
{
    meso_ref_relief r;
    memset(&r, 0, sizeof(r));
    r.height.kind = 1;
    r.height.w = w;
    r.height.h = h;
    r.height.d = 1;
    r.height.values = vals;
    return r;
}

/* Bilinear, wrapping, texel centres at (i + ½)/n — written out again here
 * for one axis (the other constant). */
static double bilinear_1d(const float* v, uint32_t n, uint32_t stride, double s)
{
    double x = (s - floor(s)) * n - 0.5, fl = floor(x), f = x - fl;
    long i0 = ((long)fl % (long)n + (long)n) % (long)n, i1 = (i0 + 1) % (long)n;
    return (1 - f) * v[(size_t)i0 * stride] + f * v[(size_t)i1 * stride];
}

static double seg_size(const meso_ref_frustum* f)
{
    double dc[3] = {f->c1[0] - f->c0[0], f->c1[1] - f->c0[1], f->c1[2] - f->c0[2]};
    return sqrt(dot3(dc, dc)) + f->r0 + f->r1 + f->relief_depth;
}

/* The segment's cone grown by `dr` (same planes and caps), without relief:
 * dr = D is the relief shell's outside. */
static meso_ref_frustum grown(const meso_ref_frustum* f, double dr)
{
    meso_ref_frustum g = *f;
    g.r0 += dr;
    g.r1 += dr;
    g.relief_depth = 0;
    return g;
}

/* A ray from far outside towards a random point near the segment. */
static void random_ray(uint64_t* rng, const meso_ref_frustum* f, double o[3], double d[3])
{
    double ctr[3], dir[3], size = seg_size(f);
    for (int i = 0; i < 3; ++i)
        ctr[i] = 0.5 * (f->c0[i] + f->c1[i]);
    rand_unit(rng, dir);
    for (int i = 0; i < 3; ++i) {
        o[i] = ctr[i] + 3 * size * dir[i];
        d[i] = ctr[i] + test_rng_uniform(rng, -0.45, 0.45) * size - o[i];
    }
    normalize3(d);
}

/* Constant h: the relief solid is the plain frustum of radii r + h·D with
 * the same planes and caps. */
static void test_relief_constant(void)
{
    uint64_t rng = 0xc0ffeeULL;
    float vals[16];
    uint32_t rays = 0, hits = 0, mismatch = 0;
    double worst = 0, samples = 0;
    for (int fi = 0; fi < 120; ++fi) {
        meso_ref_frustum f;
        random_frustum(&rng, fi % 5, &f);
        const double h = test_rng_uniform(&rng, 0, 1);
        for (int i = 0; i < 16; ++i)
            vals[i] = (float)h;
        const double hv = vals[0];
        f.relief_depth = test_rng_uniform(&rng, 0.05, 0.4);
        f.u_scale = floor(test_rng_uniform(&rng, 1, 4));
        f.v_scale = test_rng_uniform(&rng, 0.5, 2);
        f.v_offset = test_rng_uniform(&rng, 0, 1);
        meso_ref_relief rl = make_relief(vals, 4, 4);
        const meso_ref_frustum big = grown(&f, hv * f.relief_depth), outer = grown(&f, f.relief_depth);
        const double size = seg_size(&f);
        for (int ri = 0; ri < 40; ++ri) {
            double o[3], d[3];
            random_ray(&rng, &f, o, d);
            if (meso_ref_frustum_contains(&outer, o))
                continue;
            meso_ref_frustum_hit a, b;
            const int ga = meso_ref_frustum_intersect_relief(&f, &rl, o, d, 0, 100, &a);
            const int gb = meso_ref_frustum_intersect(&big, o, d, 0, 100, &b);
            ++rays;
            samples += a.steps;
            if (ga != gb) {
                /* Only a graze thinner than the step may differ: the plain
                 * chord through the solid is then tiny. */
                ++mismatch;
                double chord = 0;
                if (gb) {
                    meso_ref_frustum_hit c;
                    if (meso_ref_frustum_intersect(&big, o, d, b.t + 1e-12, 100, &c))
                        chord = c.t - b.t;
                }
                assert(gb && chord < 1e-3 * size);
                continue;
            }
            if (!ga)
                continue;
            ++hits;
            const double err = fabs(a.t - b.t) / size;
            worst = fmax(worst, err);
            if (err > 1e-9 || a.part != b.part)
                fprintf(stderr, "frustum %d ray %d: relief t %.12g part %d, cone t %.12g part %d\n", fi, ri, a.t,
                    (int)a.part, b.t, (int)b.part);
            assert(err <= 1e-9 && a.part == b.part && a.relief == 1);
            if (a.part == MESO_REF_PART_LATERAL)
                assert(fabs(a.w - hv) < 1e-6);
        }
    }
    fprintf(stderr, "    %u rays, %u hits: worst |dt|/size %.2e; %u grazes missed; %.0f samples per ray\n", rays, hits,
        worst, mismatch, samples / rays);
    assert(hits > rays / 4 && mismatch * 200 <= rays);
}

/* A cylinder along z (radius R, length L, perpendicular cuts, frame x). */
static meso_ref_frustum cylinder(double R, double L, double D)
{
    meso_ref_frustum f;
    memset(&f, 0, sizeof(f));
    f.c1[2] = L;
    f.r0 = f.r1 = R;
    f.plane_n[0][2] = -1;
    f.plane_n[1][2] = 1;
    f.plane_d[1] = L;
    f.frame_x[0] = 1;
    f.relief_depth = D;
    f.u_scale = 1;
    f.v_scale = 1;
    return f;
}

static void test_relief_step_cylinder(void)
{
    const double R = 0.5, L = 2, D = 0.2;
    meso_ref_frustum f = cylinder(R, L, D);
    const double size = seg_size(&f); /* the bisection's tolerance is 1e-9 of it */
    /* Step along t: rows 0..7 at 1, rows 8..15 at 0 (4 columns alike). Side
     * on, a ray at height z keeps t = z/L, so it meets the cylinder of
     * radius R + D·h(t). */
    float rows[4 * 16];
    for (int j = 0; j < 16; ++j)
        for (int i = 0; i < 4; ++i)
            rows[4 * j + i] = j < 8 ? 1.0f : 0.0f;
    meso_ref_relief rl = make_relief(rows, 4, 16);
    uint64_t rng = 0x5eedULL;
    int checked = 0, ramp = 0;
    double worst = 0;
    for (int k = 0; k < 4000; ++k) {
        const double z = test_rng_uniform(&rng, 1e-3, L - 1e-3), x = test_rng_uniform(&rng, -0.75, 0.75);
        const double rho = R + D * bilinear_1d(rows, 16, 4, z / L);
        if (fabs(fabs(x) - rho) < 1e-6)
            continue; /* the silhouette itself */
        const double o[3] = {x, -5, z}, d[3] = {0, 1, 0};
        meso_ref_frustum_hit h;
        const int got = meso_ref_frustum_intersect_relief(&f, &rl, o, d, 0, 100, &h);
        if (got != (fabs(x) < rho))
            fprintf(stderr, "z %.9g x %.9g: rho %.9g, got %d (t %.9g w %.9g)\n", z, x, rho, got, h.t, h.w);
        assert(got == (fabs(x) < rho));
        if (!got)
            continue;
        const double want = 5 - sqrt(rho * rho - x * x);
        worst = fmax(worst, fabs(h.t - want));
        if (!(fabs(h.t - want) < 1e-9 * size && h.part == MESO_REF_PART_LATERAL))
            fprintf(stderr, "z %.9g x %.9g: rho %.9g, t %.12g want %.12g part %d w %.9g\n", z, x, rho, h.t, want,
                (int)h.part, h.w);
        assert(fabs(h.t - want) < 1e-9 * size && h.part == MESO_REF_PART_LATERAL);
        ++checked;
        double fz = z / L * 16 - 0.5;
        ramp += fz - floor(fz) > 0.01 && fz - floor(fz) < 0.99 && ((int)floor(fz) == 7 || (int)floor(fz) == -1);
    }
    /* Step along s (one row): a radial ray keeps u, so it meets the
     * cylinder of radius R + D·h(s). u = atan2(q·x, q·z)/2π with x = (1,0,0),
     * z = x × a = (0,−1,0). */
    float cols[16];
    for (int i = 0; i < 16; ++i)
        cols[i] = i < 8 ? 1.0f : 0.0f;
    meso_ref_relief rs = make_relief(cols, 16, 1);
    for (int k = 0; k < 2000; ++k) {
        const double phi = test_rng_uniform(&rng, 0, TAU), z = test_rng_uniform(&rng, 0.01, L - 0.01);
        const double dir[3] = {cos(phi), sin(phi), 0};
        double u = atan2(dir[0], -dir[1]) / TAU;
        u -= floor(u);
        const double rho = R + D * bilinear_1d(cols, 16, 1, u);
        const double o[3] = {5 * dir[0], 5 * dir[1], z}, d[3] = {-dir[0], -dir[1], 0};
        meso_ref_frustum_hit h;
        assert(meso_ref_frustum_intersect_relief(&f, &rs, o, d, 0, 100, &h));
        worst = fmax(worst, fabs(h.t - (5 - rho)));
        assert(fabs(h.t - (5 - rho)) < 1e-9 * size);
        ++checked;
    }
    fprintf(stderr,
        "    %d side-on and radial rays (%d on the ramp between rows 7 and 8 or 15 and 0): worst |dt|/size %.2e\n",
        checked, ramp, worst / size);
    assert(ramp > 50);
}

/* v by eq. 7 literally: along the generator of the cone through p (the
 * line through p with direction a + k q̂), find where it crosses each plane
 * by sampling and bisection, then the distance ratio. */
static void test_relief_v_generator(void)
{
    uint64_t rng = 0xfeedULL;
    int checked = 0;
    double worst = 0;
    for (int fi = 0; fi < 200; ++fi) {
        meso_ref_frustum f;
        random_frustum(&rng, fi % 5, &f);
        if (!valid_cut(&f))
            continue;
        f.relief_depth = 0.3;
        double a[3] = {f.c1[0] - f.c0[0], f.c1[1] - f.c0[1], f.c1[2] - f.c0[2]};
        const double h = sqrt(dot3(a, a)), k = (f.r1 - f.r0) / h;
        normalize3(a);
        for (int pi = 0; pi < 10; ++pi) {
            double w[3];
            rand_unit(&rng, w);
            const double m = dot3(w, a);
            for (int i = 0; i < 3; ++i)
                w[i] -= m * a[i];
            normalize3(w);
            const double y = test_rng_uniform(&rng, 0.1, 0.9) * h, ry = f.r0 + k * y;
            const double delta = test_rng_uniform(&rng, -0.5 * ry, f.relief_depth);
            double p[3], g[3];
            for (int i = 0; i < 3; ++i) {
                p[i] = f.c0[i] + y * a[i] + (ry + delta) * w[i];
                g[i] = a[i] + k * w[i];
            }
            if (!meso_ref_frustum_contains(&(meso_ref_frustum){.c0 = {f.c0[0], f.c0[1], f.c0[2]},
                    .c1 = {f.c1[0], f.c1[1], f.c1[2]}, .r0 = 1e9, .r1 = 1e9,
                    .plane_n = {{f.plane_n[0][0], f.plane_n[0][1], f.plane_n[0][2]},
                        {f.plane_n[1][0], f.plane_n[1][1], f.plane_n[1][2]}},
                    .plane_d = {f.plane_d[0], f.plane_d[1]}}, p))
                continue; /* outside the planes */
            double P[2][3];
            for (int e = 0; e < 2; ++e) {
                /* plane e is crossed going backwards (e = 0) or forwards */
                const double sgn = e ? 1.0 : -1.0, span = 4 * seg_size(&f);
                double lo = 0, hi = -1;
                for (int st = 1; st <= 20000; ++st) {
                    const double lam = sgn * span * st / 20000;
                    double x[3];
                    for (int i = 0; i < 3; ++i)
                        x[i] = p[i] + lam * g[i];
                    if (dot3(f.plane_n[e], x) > f.plane_d[e]) {
                        lo = sgn * span * (st - 1) / 20000;
                        hi = lam;
                        break;
                    }
                }
                assert(hi != -1);
                for (int b = 0; b < 80; ++b) {
                    const double mid = 0.5 * (lo + hi);
                    double x[3];
                    for (int i = 0; i < 3; ++i)
                        x[i] = p[i] + mid * g[i];
                    if (dot3(f.plane_n[e], x) > f.plane_d[e])
                        hi = mid;
                    else
                        lo = mid;
                }
                for (int i = 0; i < 3; ++i)
                    P[e][i] = p[i] + 0.5 * (lo + hi) * g[i];
            }
            double d0[3], d01[3];
            for (int i = 0; i < 3; ++i) {
                d0[i] = p[i] - P[0][i];
                d01[i] = P[1][i] - P[0][i];
            }
            const double vb = sqrt(dot3(d0, d0)) / sqrt(dot3(d01, d01));
            double u, v, s, t, ww;
            meso_ref_frustum_uv(&f, p, &u, &v, NULL);
            meso_ref_frustum_relief_coords(&f, p, &s, &t, &ww);
            worst = fmax(worst, fabs(v - vb));
            assert(fabs(v - vb) < 1e-9);
            assert(fabs(ww - delta / f.relief_depth) < 1e-9);
            assert(fabs(t - (f.v_offset + v * f.v_scale)) < 1e-12 && fabs(s - u * f.u_scale) < 1e-12);
            ++checked;
        }
    }
    fprintf(stderr, "    %d points (delta from -r/2 to D): worst |v - v_brute| %.2e\n", checked, worst);
    assert(checked > 500);
}

/* A smooth height field: sums of sines over a W × H grid. */
static void smooth_field(float* v, uint32_t w, uint32_t h)
{
    for (uint32_t j = 0; j < h; ++j)
        for (uint32_t i = 0; i < w; ++i)
            v[j * w + i] = (float)(0.5 + 0.25 * sin(TAU * 2 * i / w) * cos(TAU * j / h) + 0.2 * sin(TAU * 3 * j / h));
}

/* The true relief normal against the cross product of hits of rays a small
 * distance apart (same bilinear cell, so the surface is smooth there); and
 * the shading normal equal to it where eq. 8 is the cone's normal
 * (cylinders cut perpendicularly, twisted and not). */
static void test_relief_normals(void)
{
    float vals[32 * 16];
    smooth_field(vals, 32, 16);
    meso_ref_relief rl = make_relief(vals, 32, 16);
    uint64_t rng = 0xbeefULL;
    double worst = 0, worst_sn_cyl = 0, sn_dev_max = 0;
    int checked = 0;
    for (int fi = 0; fi < 30; ++fi) {
        meso_ref_frustum f;
        const int cyl = fi % 3 == 0;
        if (cyl) {
            f = cylinder(0.5, 2, 0.15);
            f.u_scale = 2;
            f.v_scale = 1.5;
            f.twist = fi % 2 ? 1.3 : 0; /* the twist's share of ∂h/∂s along T_v (FORMAT.md) */
        } else {
            do
                random_frustum(&rng, fi % 2, &f);
            while (!valid_cut(&f));
            f.relief_depth = 0.3 * (f.r0 < f.r1 ? f.r0 : f.r1);
            f.u_scale = 2;
            f.v_scale = 1;
        }
        const double size = seg_size(&f), eps = 1e-4 * size;
        for (int ri = 0; ri < 40; ++ri) {
            double o[3], d[3];
            random_ray(&rng, &f, o, d);
            meso_ref_frustum_hit h0, hn[4];
            if (!meso_ref_frustum_intersect_relief(&f, &rl, o, d, 0, 100, &h0) || h0.part != MESO_REF_PART_LATERAL)
                continue;
            /* four rays at ±eps along two directions ⟂ d: central differences */
            double e[2][3];
            any_perp(d, e[0]);
            e[1][0] = d[1] * e[0][2] - d[2] * e[0][1];
            e[1][1] = d[2] * e[0][0] - d[0] * e[0][2];
            e[1][2] = d[0] * e[0][1] - d[1] * e[0][0];
            int same = 1;
            for (int k = 0; k < 4 && same; ++k) {
                double ok[3];
                for (int i = 0; i < 3; ++i)
                    ok[i] = o[i] + (k & 1 ? -eps : eps) * e[k >> 1][i];
                same = meso_ref_frustum_intersect_relief(&f, &rl, ok, d, 0, 100, &hn[k]) &&
                       hn[k].part == MESO_REF_PART_LATERAL && fabs(hn[k].t - h0.t) < 50 * eps;
                /* same bilinear cell (the surface is smooth inside one) */
                for (int c = 0; c < 2 && same; ++c) {
                    const double n = c ? 16 : 32;
                    same = floor(h0.tex[c] * n - 0.5) == floor(hn[k].tex[c] * n - 0.5);
                }
            }
            if (!same)
                continue;
            double a1[3], a2[3], nf[3];
            for (int i = 0; i < 3; ++i) {
                a1[i] = hn[0].p[i] - hn[1].p[i];
                a2[i] = hn[2].p[i] - hn[3].p[i];
            }
            nf[0] = a1[1] * a2[2] - a1[2] * a2[1];
            nf[1] = a1[2] * a2[0] - a1[0] * a2[2];
            nf[2] = a1[0] * a2[1] - a1[1] * a2[0];
            normalize3(nf);
            const double c = fabs(dot3(nf, h0.normal));
            const double ang = acos(fmin(1.0, c));
            worst = fmax(worst, ang);
            if (ang > 1e-3)
                fprintf(stderr, "frustum %d ray %d: normal off by %.2e rad (t %.9g, n·d %.3f)\n", fi, ri, ang, h0.t,
                    dot3(h0.normal, d));
            assert(ang < 1e-3);
            assert(fabs(dot3(h0.normal, h0.normal) - 1) < 1e-12 && fabs(dot3(h0.shading_normal, h0.shading_normal) - 1) < 1e-12);
            const double sd = acos(fmin(1.0, dot3(h0.normal, h0.shading_normal)));
            if (cyl)
                worst_sn_cyl = fmax(worst_sn_cyl, sd);
            else
                sn_dev_max = fmax(sn_dev_max, sd);
            ++checked;
        }
    }
    fprintf(stderr,
        "    %d hits: normal vs finite differences worst %.2e rad; shading vs true normal: cylinder %.2e rad, "
        "tapered/oblique frusta up to %.3f rad\n",
        checked, worst, worst_sn_cyl, sn_dev_max);
    assert(checked > 200);
    assert(worst_sn_cyl < 1e-6);
}

/* Random height fields: the first point of the relief solid found by a
 * uniform world-space march (step 1/64 of the texel bound's world size,
 * bisected on point-in-solid) against the reference's hit. */
static int relief_solid(const meso_ref_frustum* f, const meso_ref_relief* rl, const double p[3])
{
    const meso_ref_frustum outer = grown(f, f->relief_depth);
    if (!meso_ref_frustum_contains(&outer, p))
        return 0;
    double s, t, w;
    meso_ref_frustum_relief_coords(f, p, &s, &t, &w);
    return w <= meso_ref_texfn_value(&rl->height, s, t, 0);
}

static void test_relief_march(void)
{
    uint64_t rng = 0x0ddba11ULL;
    float vals[16 * 16];
    int checked = 0, hits = 0, grazes = 0;
    double worst = 0, samples = 0;
    for (int fi = 0; fi < 30; ++fi) {
        meso_ref_frustum f;
        do
            random_frustum(&rng, fi % 2, &f);
        while (!valid_cut(&f));
        for (int i = 0; i < 256; ++i)
            vals[i] = (float)test_rng_uniform(&rng, 0, 1);
        meso_ref_relief rl = make_relief(vals, 16, 16);
        f.relief_depth = 0.4 * (f.r0 < f.r1 ? f.r0 : f.r1);
        f.u_scale = 1;
        f.v_scale = 1;
        f.cap[0] = f.cap[1] = 0;
        const double size = seg_size(&f);
        /* a texel is at least 2π r_min / 16 around and (length)/16 along */
        const double rmin = f.r0 < f.r1 ? f.r0 : f.r1;
        const double texel = fmin(TAU * rmin / 16, (size - f.r0 - f.r1 - f.relief_depth) / 16);
        const double dt = fmin(texel, f.relief_depth) / 8 / 64;
        const meso_ref_frustum outer = grown(&f, f.relief_depth);
        for (int ri = 0; ri < 25; ++ri) {
            double o[3], d[3];
            random_ray(&rng, &f, o, d);
            meso_ref_frustum_hit oh, h;
            if (!meso_ref_frustum_intersect(&outer, o, d, 0, 100, &oh) || dot3(oh.normal, d) > 0)
                continue; /* the ray misses the shell (or starts inside) */
            meso_ref_frustum_hit ox;
            double t1 = oh.t + 2 * size;
            if (meso_ref_frustum_intersect(&outer, o, d, oh.t + 1e-9, 100, &ox))
                t1 = ox.t;
            double tin = -1;
            for (double t = oh.t; t <= t1 + dt && tin < 0; t += dt) {
                double p[3];
                at(o, d, t, p);
                if (!relief_solid(&f, &rl, p))
                    continue;
                double lo = t - dt, hi = t;
                for (int b = 0; b < 60; ++b) {
                    const double mid = 0.5 * (lo + hi);
                    at(o, d, mid, p);
                    if (relief_solid(&f, &rl, p))
                        hi = mid;
                    else
                        lo = mid;
                }
                tin = hi;
            }
            const int got = meso_ref_frustum_intersect_relief(&f, &rl, o, d, 0, 100, &h);
            samples += h.steps;
            ++checked;
            if (tin < 0 && !got)
                continue;
            if (got && (tin < 0 || h.t > tin + 1e-8 * size)) {
                /* the reference stepped over what the march found: only a
                 * graze may do that */
                ++grazes;
                fprintf(stderr, "    frustum %d ray %d: march enters at %.9g, reference at %.9g\n", fi, ri, tin,
                    got ? h.t : -1.0);
                continue;
            }
            assert(got);
            ++hits;
            worst = fmax(worst, fabs(h.t - tin) / size);
            assert(fabs(h.t - tin) <= 1e-8 * size);
        }
    }
    fprintf(stderr, "    %d rays, %d hits: worst |dt|/size %.2e, %d grazes, %.0f samples per ray\n", checked, hits,
        worst, grazes, samples / checked);
    assert(hits > checked / 3 && grazes * 100 <= checked);
}

/* FRUS/FSEG records → reference segments. */
static void test_from_records(void)
{
    meso_frustum_rec rec;
    memset(&rec, 0, sizeof(rec));
    const float c0[3] = {1, 2, 3}, c1[3] = {1, 2, 5};
    memcpy(rec.center[0], c0, sizeof(c0));
    memcpy(rec.center[1], c1, sizeof(c1));
    rec.radius[0] = 0.5f;
    rec.radius[1] = 0.25f;
    rec.plane[0][2] = -1;
    rec.plane[1][2] = 1;
    rec.flags = MESO_FSEG_CAP1;
    rec.frame_x[0] = 1;
    rec.u_offset = 0.25f;
    rec.u_scale = 3;
    rec.v_offset = 0.5f;
    rec.v_scale = 2;
    rec.relief_depth = 0.125f;
    meso_ref_frustum f;
    meso_ref_frustum_from_rec(&rec, &f);
    assert(f.plane_d[0] == -3 && f.plane_d[1] == 5 && !f.cap[0] && f.cap[1]);
    assert(f.r0 == 0.5 && f.r1 == 0.25 && f.u_scale == 3 && f.v_offset == 0.5 && f.v_scale == 2 &&
           f.relief_depth == 0.125 && f.u_offset == 0.25);
    meso_frustum_ball_rec br = {{1, 2, 3}, 0.75f, 4};
    meso_ref_ball b;
    meso_ref_ball_from_rec(&br, &b);
    assert(b.center[2] == 3 && b.radius == 0.75);
}

int main(void)
{
    TEST_RUN(test_closed_form);
    TEST_RUN(test_brute_force);
    TEST_RUN(test_model_loop);
    TEST_RUN(test_relief_constant);
    TEST_RUN(test_relief_step_cylinder);
    TEST_RUN(test_relief_v_generator);
    TEST_RUN(test_relief_normals);
    TEST_RUN(test_relief_march);
    TEST_RUN(test_from_records);
    return 0;
}
