/*
 * test_frustum_reference.c — the exact ray–frustum intersection
 * (runtime/reference/frustum_reference.c) against brute force: rays are
 * marched in world space with a fine step, point-in-solid (inside the cone,
 * on its nappe, between both planes) brackets the first entry, and
 * bisection on the same predicate narrows it to 1e-12; the analytic t must
 * agree. Random frusta: oblique planes (up to 30°), cylinders, zero-radius
 * tips and radius jumps (radius far larger than the length).
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

int main(void)
{
    TEST_RUN(test_closed_form);
    TEST_RUN(test_brute_force);
    TEST_RUN(test_model_loop);
    return 0;
}
