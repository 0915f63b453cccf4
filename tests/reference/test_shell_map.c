/*
 * test_shell_map.c — the double-precision shell mappings and the CPU
 * reference ray caster (runtime/reference). Expectations come from direct
 * evaluation or closed-form answers, never from earlier runs; the measured
 * numbers (the paper's §4.2 bisection error, eq. 2's error, the curved
 * shell's tangent continuity, how often curved shells leave their prism) are
 * printed for the record.
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "meso_file.h"
#include "shell_map.h"
#include "shell_reference.h"

static int failures;

#define CHECK(c)                                                                 \
    do {                                                                         \
        if (!(c)) {                                                              \
            fprintf(stderr, "%s:%d: check failed: %s\n", __FILE__, __LINE__, #c); \
            ++failures;                                                          \
        }                                                                        \
    } while (0)

/* >>helpers ---------------------------------------------------------------- */

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static double rnd(void) /* [0, 1) */
{
    rng_state ^= rng_state << 13;
    rng_state ^= rng_state >> 7;
    rng_state ^= rng_state << 17;
    return (double)(rng_state >> 11) / 9007199254740992.0;
}

static double rnd_in(double a, double b)
{
    return a + (b - a) * rnd();
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void cross(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static void normalize(double v[3])
{
    const double l = sqrt(dot(v, v));
    for (int i = 0; i < 3; ++i)
        v[i] /= l;
}

static double angle_deg(const double a[3], const double b[3])
{
    double c[3];
    cross(a, b, c);
    return atan2(sqrt(dot(c, c)), dot(a, b)) * 180.0 / M_PI;
}

/* Random point in the prism's domain, kept `m` away from its faces. */
static void rnd_uvw(double m, double q[3])
{
    double u, v;
    do {
        u = rnd();
        v = rnd();
    } while (u + v > 1);
    const double s = 1 - 3 * m;
    q[0] = m + s * u;
    q[1] = m + s * v;
    q[2] = m + (1 - 2 * m) * rnd();
}

/* A random twisted prism: a triangle of edge ~1, directors of length
 * 0.2..0.6 along its normal tilted by up to ~30° each, in different
 * directions (non-parallel), all on the same side. */
static void random_prism(meso_prism* P)
{
    for (;;) {
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 3; ++c)
                P->b[k][c] = rnd_in(-1, 1);
        double e1[3], e2[3], n[3];
        for (int c = 0; c < 3; ++c) {
            e1[c] = P->b[1][c] - P->b[0][c];
            e2[c] = P->b[2][c] - P->b[0][c];
        }
        cross(e1, e2, n);
        const double area = 0.5 * sqrt(dot(n, n));
        const double l1 = sqrt(dot(e1, e1)), l2 = sqrt(dot(e2, e2));
        if (area < 0.25 * l1 * l2 * 0.5 || l1 < 0.5 || l2 < 0.5) /* reject slivers */
            continue;
        normalize(n);
        for (int k = 0; k < 3; ++k) {
            const double len = rnd_in(0.2, 0.6);
            for (int c = 0; c < 3; ++c)
                P->n[k][c] = len * (n[c] + rnd_in(-0.3, 0.3));
        }
        for (int k = 0; k < 3; ++k)
            for (int c = 0; c < 2; ++c)
                P->uv[k][c] = rnd();
        return;
    }
}

/* The paper's §4.2 bisection on w, as it states it: 12 steps from [0, 1],
 * the sign of dot(n(T(w)), p − A0) picking the half. */
static double paper_bisection_w(const meso_prism* P, const double p[3], int steps)
{
    double lo = 0, hi = 1;
    for (int i = 0; i < steps; ++i) {
        const double m = 0.5 * (lo + hi);
        double a[3][3], e1[3], e2[3], n[3], d[3];
        meso_prism_level(P, m, a);
        for (int c = 0; c < 3; ++c) {
            e1[c] = a[1][c] - a[0][c];
            e2[c] = a[2][c] - a[0][c];
            d[c] = p[c] - a[0][c];
        }
        cross(e1, e2, n);
        if (dot(n, d) > 0)
            lo = m;
        else
            hi = m;
    }
    return 0.5 * (lo + hi);
}

/* >>smooth map ------------------------------------------------------------- */

static void test_smooth(void)
{
    double err_bary = 0, err_inv = 0, err_bis = 0, err_bis_uv = 0;
    int refused = 0, outside = 0;
    for (int it = 0; it < 200; ++it) {
        meso_prism P;
        random_prism(&P);
        for (int s = 0; s < 50; ++s) {
            double q[3], p[3], a[3][3], u, v;
            rnd_uvw(0.01, q);
            meso_phi(&P, q[0], q[1], q[2], p);
            /* Φ by the letter of eq. 1, independently of meso_phi. */
            const double t = 1 - q[0] - q[1];
            for (int c = 0; c < 3; ++c) {
                const double direct = t * P.b[0][c] + q[0] * P.b[1][c] + q[1] * P.b[2][c] +
                                      q[2] * (t * P.n[0][c] + q[0] * P.n[1][c] + q[1] * P.n[2][c]);
                CHECK(fabs(direct - p[c]) <= 1e-14);
            }
            meso_prism_level(&P, q[2], a);
            CHECK(meso_barycentric((const double(*)[3])a, p, &u, &v));
            err_bary = fmax(err_bary, fmax(fabs(u - q[0]), fabs(v - q[1])));
            double r[3] = {0, 0, 0};
            CHECK(meso_phi_inverse(&P, p, 0, 1, 1e-9, r));
            for (int c = 0; c < 3; ++c)
                err_inv = fmax(err_inv, fabs(r[c] - q[c]));
            const double wb = paper_bisection_w(&P, p, 12);
            err_bis = fmax(err_bis, fabs(wb - q[2]));
            meso_prism_level(&P, wb, a);
            if (meso_barycentric((const double(*)[3])a, p, &u, &v))
                err_bis_uv = fmax(err_bis_uv, fmax(fabs(u - q[0]), fabs(v - q[1])));
        }
        /* Points outside the prism, beyond the inverse's tolerance: above,
         * below, or past one of the side patches. */
        for (int s = 0; s < 20; ++s) {
            double q[3], p[3], r[3];
            rnd_uvw(0.05, q);
            const int side = s % 4;
            if (side == 0)
                q[2] = rnd_in(1.02, 1.3);
            else if (side == 1)
                q[2] = rnd_in(-0.3, -0.02);
            else if (side == 2)
                q[0] = rnd_in(-0.2, -0.02);
            else
                q[0] = 1.02 - q[1] + rnd() * 0.1;
            meso_phi(&P, q[0], q[1], q[2], p);
            ++outside;
            refused += !meso_phi_inverse(&P, p, 0, 1, 1e-9, r);
        }
    }
    printf("smooth: barycentric correspondence max error %.3g, exact inverse max error %.3g, %d/%d outside points "
           "refused\n",
           err_bary, err_inv, refused, outside);
    printf("smooth: paper 4.2 bisection (12 steps on [0,1]) max |w - w_exact| = %.3g (2^-13 = %.3g), its (u,v) max "
           "error %.3g\n",
           err_bis, ldexp(1, -13), err_bis_uv);
    CHECK(err_bary <= 1e-12);
    CHECK(err_inv <= 1e-12);
    CHECK(refused == outside);
    CHECK(err_bis <= ldexp(1, -13) * 1.0001);

    /* A degenerate cubic: parallel directors of equal length make the
     * determinant linear in w (T(w) a translate of T(0)); a prism with
     * directors in its plane's normal but different lengths makes it
     * quadratic. Both must still invert exactly. */
    meso_prism Q = {.b = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, .n = {{0, 0, 0.5}, {0, 0, 0.5}, {0, 0, 0.5}}};
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1) {
            Q.n[1][2] = 0.8;
            Q.n[2][2] = 0.3;
        }
        double emax = 0;
        for (int s = 0; s < 200; ++s) {
            double q[3], p[3], r[3] = {0, 0, 0};
            rnd_uvw(0.001, q);
            meso_phi(&Q, q[0], q[1], q[2], p);
            CHECK(meso_phi_inverse(&Q, p, 0, 1, 1e-9, r));
            for (int c = 0; c < 3; ++c)
                emax = fmax(emax, fabs(r[c] - q[c]));
        }
        CHECK(emax <= 1e-12);
    }
}

/* >>curved map ------------------------------------------------------------- */

/* Prism on the unit sphere: vertices at the given points, directors
 * h · (unit position). */
static void sphere_prism(const double v[3][3], double h, meso_prism* P)
{
    memset(P, 0, sizeof(*P));
    for (int k = 0; k < 3; ++k) {
        double n[3] = {v[k][0], v[k][1], v[k][2]};
        normalize(n);
        for (int c = 0; c < 3; ++c) {
            P->b[k][c] = n[c];
            P->n[k][c] = h * n[c];
        }
    }
}

static void sph(double theta, double phi, double o[3])
{
    o[0] = sin(theta) * cos(phi);
    o[1] = sin(theta) * sin(phi);
    o[2] = cos(theta);
}

/* Unit normal of the level surface w of a prism's map at (u, v), facing
 * along the directors: central differences of the map's own formula. */
static void level_normal(const meso_prism* P, int curved, double u, double v, double w, double n[3])
{
    const double h = 1e-6;
    double pu0[3], pu1[3], pv0[3], pv1[3], du[3], dv[3];
    void (*map)(const meso_prism*, double, double, double, double*) = curved ? meso_phi_curved : meso_phi;
    map(P, u + h, v, w, pu1);
    map(P, u - h, v, w, pu0);
    map(P, u, v + h, w, pv1);
    map(P, u, v - h, w, pv0);
    for (int c = 0; c < 3; ++c) {
        du[c] = pu1[c] - pu0[c];
        dv[c] = pv1[c] - pv0[c];
    }
    cross(du, dv, n);
    normalize(n);
    double d[3];
    for (int c = 0; c < 3; ++c)
        d[c] = (1 - u - v) * P->n[0][c] + u * P->n[1][c] + v * P->n[2][c];
    if (dot(n, d) < 0)
        for (int c = 0; c < 3; ++c)
            n[c] = -n[c];
}

typedef struct pair_stats {
    double edge_gap, angle_curved, angle_smooth, eq2_err, eq2_err_glsl, inv_err, leave_fraction;
    int wbar_monotone;
} pair_stats;

/* Two prisms sharing the edge V0 V1 (A = V0 V1 V2, B = V1 V0 V3), directors
 * along the sphere's radius. */
static void pair_measure(const double V0[3], const double V1[3], const double V2[3], const double V3[3], double h,
                         pair_stats* st)
{
    const double va[3][3] = {{V0[0], V0[1], V0[2]}, {V1[0], V1[1], V1[2]}, {V2[0], V2[1], V2[2]}};
    const double vb[3][3] = {{V1[0], V1[1], V1[2]}, {V0[0], V0[1], V0[2]}, {V3[0], V3[1], V3[2]}};
    meso_prism A, B;
    sphere_prism(va, h, &A);
    sphere_prism(vb, h, &B);
    memset(st, 0, sizeof(*st));
    st->wbar_monotone = 1;
    /* Along the shared edge: A at (u,v) = (s,0) is B at (1-s,0). */
    for (int i = 1; i < 40; ++i) {
        const double s = i / 40.0;
        for (int j = 0; j <= 4; ++j) {
            const double w = j / 4.0;
            double pa[3], pb[3], na[3], nb[3];
            meso_phi_curved(&A, s, 0, w, pa);
            meso_phi_curved(&B, 1 - s, 0, w, pb);
            for (int c = 0; c < 3; ++c)
                st->edge_gap = fmax(st->edge_gap, fabs(pa[c] - pb[c]));
            level_normal(&A, 1, s, 0, w, na);
            level_normal(&B, 1, 1 - s, 0, w, nb);
            st->angle_curved = fmax(st->angle_curved, angle_deg(na, nb));
            level_normal(&A, 0, s, 0, w, na);
            level_normal(&B, 0, 1 - s, 0, w, nb);
            st->angle_smooth = fmax(st->angle_smooth, angle_deg(na, nb));
        }
    }
    /* Interior: inverse round trip, eq. 2, leaving the prism. */
    int out = 0, total = 0;
    for (int s = 0; s < 2000; ++s) {
        double q[3], p[3], r[3] = {0, 0, 0};
        rnd_uvw(0.0, q);
        const meso_prism* P = s % 2 ? &A : &B;
        const double wb = meso_curved_wbar(P, q[0], q[1], q[2]);
        ++total;
        out += wb < 0 || wb > 1;
        double prev = meso_curved_wbar(P, q[0], q[1], 0);
        for (int k = 1; k <= 16; ++k) {
            const double x = meso_curved_wbar(P, q[0], q[1], k / 16.0);
            st->wbar_monotone &= x > prev;
            prev = x;
        }
        meso_phi_curved(P, q[0], q[1], q[2], p);
        if (meso_phi_curved_inverse(P, p, 1e-9, r)) {
            for (int c = 0; c < 3; ++c)
                st->inv_err = fmax(st->inv_err, fabs(r[c] - q[c]));
        } else {
            st->inv_err = INFINITY;
        }
        /* eq. 2 with the exact (u, v), as the paper writes it ... */
        double p0[3], p1[3], d0[3], d1[3];
        meso_phi_curved(P, q[0], q[1], 0, p0);
        meso_phi_curved(P, q[0], q[1], 1, p1);
        for (int c = 0; c < 3; ++c) {
            d0[c] = p[c] - p0[c];
            d1[c] = p1[c] - p0[c];
        }
        const double w2 = sqrt(dot(d0, d0)) / sqrt(dot(d1, d1));
        st->eq2_err = fmax(st->eq2_err, fabs(w2 - q[2]));
        /* ... and as the GLSL computes it: linear in w̄. */
        const double w0 = meso_curved_wbar(P, q[0], q[1], 0), w1 = meso_curved_wbar(P, q[0], q[1], 1);
        st->eq2_err_glsl = fmax(st->eq2_err_glsl, fabs((wb - w0) / (w1 - w0) - q[2]));
    }
    st->leave_fraction = (double)out / total;
}

/* meso_curved_wbar_range is conservative: dense samples of w̄ (w = 0 and 1
 * suffice, w̄ is affine in w) never leave it — on random twisted prisms,
 * sphere-like prisms of many sizes and sharply bent ones — and it is not
 * needlessly loose (reported: sampled spread / bound spread). */
static void test_curved_range(void)
{
    double worst_over = -INFINITY, tight_sum = 0, tight_min = 1;
    int n = 0;
    for (int it = 0; it < 600; ++it) {
        meso_prism P;
        if (it < 200) {
            random_prism(&P);
        } else {
            /* Sphere patches, edge angle 0.05 .. 1.2 rad, thickness 0.01 .. 0.3. */
            const double a = 0.05 + 1.15 * (it - 200) / 400.0, th = rnd_in(0.01, 0.3);
            const double t0 = rnd_in(0.3, 2.5), p0 = rnd_in(-3, 3);
            double v[3][3];
            sph(t0, p0, v[0]);
            sph(t0 + a, p0 + rnd_in(-0.3, 0.3), v[1]);
            sph(t0 + 0.5 * a, p0 + a / sin(t0 + 0.5 * a), v[2]);
            sphere_prism((const double(*)[3])v, th, &P);
        }
        double lo, hi, mn = INFINITY, mx = -INFINITY;
        meso_curved_wbar_range(&P, &lo, &hi);
        enum { N = 40 };
        for (int i = 0; i <= N; ++i)
            for (int j = 0; i + j <= N; ++j)
                for (int k = 0; k < 2; ++k) {
                    const double wb = meso_curved_wbar(&P, (double)i / N, (double)j / N, k);
                    mn = fmin(mn, wb);
                    mx = fmax(mx, wb);
                }
        worst_over = fmax(worst_over, fmax(lo - mn, mx - hi));
        const double t = (fmax(mx, 1.0) - fmin(mn, 0.0)) / (hi - lo);
        tight_sum += t;
        tight_min = fmin(tight_min, t);
        ++n;
    }
    printf("curved w-bar range: 600 prisms, worst excess of a sample over the bound %.3g (<= 0 is conservative); "
           "sampled spread / bound spread mean %.2f, min %.2f\n",
           worst_over, tight_sum / n, tight_min);
    CHECK(worst_over <= 0);
    CHECK(tight_sum / n > 0.3);
}

static void test_curved(void)
{
    /* Sphere-like pair: a tessellation of the unit sphere with ~0.35 rad
     * edges (a few hundred triangles), shell thickness 0.05. */
    double V0[3], V1[3], V2[3], V3[3];
    sph(1.2, 0.0, V0);
    sph(1.55, 0.05, V1);
    sph(1.35, 0.35, V2);
    sph(1.4, -0.3, V3);
    pair_stats s;
    pair_measure(V0, V1, V2, V3, 0.05, &s);
    printf("curved, sphere-like pair (edges ~0.35 rad, thickness 0.05): shared-edge gap %.3g; crease angle across "
           "the edge: curved %.4f deg, smooth %.4f deg (ratio %.3f)\n",
           s.edge_gap, s.angle_curved, s.angle_smooth, s.angle_curved / s.angle_smooth);
    printf("curved, sphere-like pair: inverse round trip max error %.3g; eq. 2 max |w - w_exact| = %.4g of the "
           "thickness (linear in wbar, as the GLSL: %.4g); wbar outside [0,1]: %.2f%% of samples; wbar monotone in w: "
           "%s\n",
           s.inv_err, s.eq2_err, s.eq2_err_glsl, 100 * s.leave_fraction, s.wbar_monotone ? "yes" : "no");
    CHECK(s.edge_gap <= 1e-12);
    /* Tangent continuity: the curved shell's crease is a small fraction of
     * the flat (smooth) shell's at the same edge. The construction is only
     * approximately G1 (heights go along the interpolated director, not
     * along the Hermite curves' normals), so not zero. */
    CHECK(s.angle_smooth > 5.0);
    CHECK(s.angle_curved <= 0.05 * s.angle_smooth);
    CHECK(s.inv_err <= 1e-9);
    CHECK(s.wbar_monotone);
    /* The paper reports eq. 2 within 1/100 of the thickness. With meso's
     * construction it is exact: A_k = B_k + w' N_k is affine in w' and the
     * unit normals m_k, M_j, M_k and the weights ω_i, r do not depend on w',
     * so every height and slope, hence Coons(λ), is affine in w' and w̄ is
     * affine in w. Only rounding is left (checked again on random twisted
     * prisms below). */
    CHECK(s.eq2_err <= 1e-12 && s.eq2_err_glsl <= 1e-12);

    /* Sharply bent pair: normals ~70° apart across the edge, thicker shell. */
    sph(0.6, 0.0, V0);
    sph(1.8, 0.1, V1);
    sph(1.3, 0.9, V2);
    sph(1.1, -0.9, V3);
    pair_measure(V0, V1, V2, V3, 0.1, &s);
    printf("curved, sharply bent pair (edges ~1.2 rad, thickness 0.1): shared-edge gap %.3g; crease curved %.3f deg "
           "vs smooth %.3f deg; inverse max error %.3g; eq. 2 max error %.4g of the thickness (GLSL form %.4g); wbar "
           "outside [0,1] (the shell leaves its prism): %.1f%% of samples\n",
           s.edge_gap, s.angle_curved, s.angle_smooth, s.inv_err, s.eq2_err, s.eq2_err_glsl, 100 * s.leave_fraction);
    CHECK(s.edge_gap <= 1e-12);
    CHECK(s.angle_curved < s.angle_smooth);
    CHECK(s.inv_err <= 1e-9);
    CHECK(s.leave_fraction > 0); /* the paper's §3.2 caveat, seen */

    /* w̄ is affine in w on any prism, not only on spheres: eq. 2 on random
     * twisted prisms with non-parallel directors. */
    double e2 = 0, e_inv = 0;
    for (int it = 0; it < 200; ++it) {
        meso_prism P;
        random_prism(&P);
        for (int k = 0; k < 20; ++k) {
            double q[3], p[3], p0[3], p1[3], d0[3], d1[3], r[3] = {0, 0, 0};
            rnd_uvw(0.0, q);
            meso_phi_curved(&P, q[0], q[1], q[2], p);
            meso_phi_curved(&P, q[0], q[1], 0, p0);
            meso_phi_curved(&P, q[0], q[1], 1, p1);
            for (int c = 0; c < 3; ++c) {
                d0[c] = p[c] - p0[c];
                d1[c] = p1[c] - p0[c];
            }
            e2 = fmax(e2, fabs(sqrt(dot(d0, d0)) / sqrt(dot(d1, d1)) - q[2]));
            if (meso_phi_curved_inverse(&P, p, 1e-9, r))
                for (int c = 0; c < 3; ++c)
                    e_inv = fmax(e_inv, fabs(r[c] - q[c]));
            else
                e_inv = INFINITY;
        }
    }
    printf("curved, random twisted prisms: eq. 2 max error %.3g of the thickness, inverse round trip max error "
           "%.3g\n",
           e2, e_inv);
    CHECK(e2 <= 1e-12);
    CHECK(e_inv <= 1e-9);
}

/* >>texture ---------------------------------------------------------------- */

static void test_texture(void)
{
    enum { W = 5, H = 3, D = 4 };
    float vals[W * H * D];
    for (int i = 0; i < W * H * D; ++i)
        vals[i] = (float)rnd();
    meso_ref_texfn hf = {.kind = 1, .w = W, .h = H, .d = 1, .values = vals};
    meso_ref_texfn vol = {.kind = 2, .w = W, .h = H, .d = D, .values = vals};
    double e_centre = 0, e_wrap = 0, e_mid = 0, e_clamp = 0;
    for (int j = 0; j < H; ++j)
        for (int i = 0; i < W; ++i) {
            const double s = (i + 0.5) / W, t = (j + 0.5) / H;
            e_centre = fmax(e_centre, fabs(meso_ref_texfn_value(&hf, s, t, 0.3) - vals[j * W + i]));
            for (int k = 0; k < D; ++k)
                e_centre = fmax(e_centre, fabs(meso_ref_texfn_value(&vol, s, t, (k + 0.5) / D) - vals[(k * H + j) * W + i]));
            /* Halfway between two texel centres along s (wrapping at the end). */
            const double mid = 0.5 * ((double)vals[j * W + i] + (double)vals[j * W + (i + 1) % W]);
            e_mid = fmax(e_mid, fabs(meso_ref_texfn_value(&hf, (i + 1.0) / W, t, 0) - mid));
        }
    for (int n = 0; n < 200; ++n) {
        const double s = rnd(), t = rnd(), w = rnd();
        const double a = meso_ref_texfn_value(&vol, s, t, w);
        e_wrap = fmax(e_wrap, fabs(a - meso_ref_texfn_value(&vol, s + 1, t, w)));
        e_wrap = fmax(e_wrap, fabs(a - meso_ref_texfn_value(&vol, s, t - 1, w)));
        e_wrap = fmax(e_wrap, fabs(a - meso_ref_texfn_value(&vol, s - 3, t + 2, w)));
        /* Clamp in w: below the first centre / above the last one. */
        e_clamp = fmax(e_clamp, fabs(meso_ref_texfn_value(&vol, s, t, -0.4) - meso_ref_texfn_value(&vol, s, t, 0.5 / D)));
        e_clamp = fmax(e_clamp, fabs(meso_ref_texfn_value(&vol, s, t, 0.1 / D) - meso_ref_texfn_value(&vol, s, t, 0.5 / D)));
        e_clamp = fmax(e_clamp,
                       fabs(meso_ref_texfn_value(&vol, s, t, 1.7) - meso_ref_texfn_value(&vol, s, t, (D - 0.5) / D)));
    }
    printf("texture: centres %.3g, midpoints %.3g, wrap %.3g, clamp %.3g\n", e_centre, e_mid, e_wrap, e_clamp);
    CHECK(e_centre <= 1e-12);
    CHECK(e_mid <= 1e-12);
    CHECK(e_wrap <= 1e-12);
    CHECK(e_clamp <= 1e-12);
    /* Solid tests. */
    CHECK(meso_ref_texfn_solid(&hf, 0.5 / W, 0.5 / H, vals[0] - 1e-9));
    CHECK(!meso_ref_texfn_solid(&hf, 0.5 / W, 0.5 / H, vals[0] + 1e-9));
    meso_ref_texfn none = {0};
    CHECK(meso_ref_texfn_solid(&none, 0.3, 0.1, 0.99));
    double g[3];
    meso_ref_texfn_gradient(&none, 0.1, 0.2, 0.3, g);
    CHECK(g[0] == 0 && g[1] == 0 && g[2] == 1);
    /* Gradient of a height ramp (linear across the central texels). */
    float ramp[8];
    for (int i = 0; i < 8; ++i)
        ramp[i] = (float)(0.1 * i);
    meso_ref_texfn rf = {.kind = 1, .w = 8, .h = 1, .d = 1, .values = ramp};
    meso_ref_texfn_gradient(&rf, 0.5, 0.5, 0, g);
    CHECK(fabs(g[0] + (double)(ramp[5] - ramp[3]) / (2.0 / 8)) < 1e-6 && fabs(g[1]) < 1e-12 && g[2] == 1);
}

/* >>renderer --------------------------------------------------------------- */

/* Column-major orthographic projection (glOrtho). */
static void ortho(double m[16], double l, double r, double b, double t, double n, double f)
{
    memset(m, 0, 16 * sizeof(double));
    m[0] = 2 / (r - l);
    m[5] = 2 / (t - b);
    m[10] = -2 / (f - n);
    m[12] = -(r + l) / (r - l);
    m[13] = -(t + b) / (t - b);
    m[14] = -(f + n) / (f - n);
    m[15] = 1;
}

/* The unit square in z = 0 as two triangles, directors (0, 0, H), uvs =
 * (x, y); written as a .meso file (OBJT + MESH + SDIR [+ TX2D]) and loaded
 * back with meso_ref_shell_load. */
static void* square_file(double H, const uint8_t* height, uint32_t hw, uint32_t hh, size_t* size)
{
    const float pos[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    const float uvs[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    float dirs[12];
    for (int i = 0; i < 4; ++i) {
        dirs[3 * i] = 0;
        dirs[3 * i + 1] = 0;
        dirs[3 * i + 2] = (float)H;
    }
    meso_mesh_layout L;
    CHECK(meso_mesh_compute_layout(4, 6, MESO_MESH_ATTR_POSITIONS | MESO_MESH_ATTR_UVS, &L) == MESO_OK);
    uint8_t* mesh = calloc(1, (size_t)L.size);
    meso_mesh_write_header(&L, mesh);
    memcpy(mesh + L.positions_offset, pos, sizeof(pos));
    memcpy(mesh + L.uvs_offset, uvs, sizeof(uvs));
    memcpy(mesh + L.indices_offset, idx, sizeof(idx));
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_SHELL, .bbox_min = {0, 0, 0}, .bbox_max = {1, 1, (float)H}};
    strcpy(rec.name, "square");
    uint8_t objt[64];
    meso_object_record_encode(&rec, objt);
    meso_writer* w = NULL;
    CHECK(meso_writer_create(NULL, &w) == MESO_OK);
    meso_error err;
    meso_chunk_desc d = {.type = MESO_CHUNK_OBJT, .flags = MESO_CHUNK_FLAG_REQUIRED, .dtype = MESO_DTYPE_BYTES,
                         .dims = {1, 1, 1}};
    CHECK(meso_writer_add(w, &d, objt, sizeof(objt), &err) == MESO_OK);
    d = (meso_chunk_desc){.type = MESO_CHUNK_MESH, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1,
                          .dtype = MESO_DTYPE_BYTES, .dims = {1, 1, 1}};
    CHECK(meso_writer_add(w, &d, mesh, (size_t)L.size, &err) == MESO_OK);
    d = (meso_chunk_desc){.type = MESO_CHUNK_SDIR, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1,
                          .dtype = MESO_DTYPE_F32, .components = 3, .dims = {4, 1, 1}};
    CHECK(meso_writer_add(w, &d, dirs, sizeof(dirs), &err) == MESO_OK);
    if (height) {
        d = (meso_chunk_desc){.type = MESO_CHUNK_TX2D, .object = 1, .dtype = MESO_DTYPE_U8, .components = 1,
                              .dims = {hw, hh, 1}};
        CHECK(meso_writer_add(w, &d, height, (size_t)hw * hh, &err) == MESO_OK);
    }
    CHECK(meso_writer_finish(w, NULL, 0, size) == MESO_OK);
    void* buf = malloc(*size);
    CHECK(meso_writer_finish(w, buf, *size, size) == MESO_OK);
    meso_writer_destroy(w);
    free(mesh);
    return buf;
}

static int load_square(double H, const uint8_t* height, uint32_t hw, uint32_t hh, meso_ref_shell* s)
{
    size_t size = 0;
    void* buf = square_file(H, height, hw, hh, &size);
    meso_file* f = NULL;
    meso_error err;
    int ok = meso_file_open_memory(buf, size, NULL, &f, &err) == MESO_OK;
    if (ok) {
        const meso_result r = meso_ref_shell_load(f, 1, s, &err);
        if (r != MESO_OK)
            fprintf(stderr, "load: %s\n", err.message);
        ok = r == MESO_OK;
    }
    meso_file_close(f);
    free(buf);
    return ok;
}

/* Top-down orthographic view of [−0.25, 1.25]² (no pixel centre on the
 * square's border), looking along −z from z = 1 to z = −1. */
static meso_ref_view top_view(int n)
{
    meso_ref_view v;
    memset(&v, 0, sizeof(v));
    for (int i = 0; i < 16; ++i)
        v.view[i] = i % 5 == 0;
    v.view[14] = -1; /* eye at z = 1 */
    ortho(v.proj, -0.25, 1.25, -0.25, 1.25, 0.0, 2.0);
    v.width = v.height = n;
    v.light_dir[0] = 0.6;
    v.light_dir[2] = 0.8;
    v.samples_per_prism = 64;
    v.threads = 1;
    return v;
}

/* Expected colour for normal n and texture height w (shell_reference.h). */
static void expect_rgb(const meso_ref_view* v, const double n[3], double w, double rgb[3])
{
    double l[3] = {v->light_dir[0], v->light_dir[1], v->light_dir[2]};
    normalize(l);
    const double k = (0.25 + 0.75 * w) * (0.15 + 0.85 * fmax(0, dot(n, l)));
    const double al[3] = {0.80, 0.74, 0.66};
    for (int c = 0; c < 3; ++c)
        rgb[c] = al[c] * k;
}

typedef struct render_check {
    int covered, coverage_wrong;
    double e_z, e_depth, e_normal, e_rgb;
} render_check;

/* Checks every pixel against the surface z = H f(x) over the unit square
 * (f given by height()), its normal (−H f'(x), 0, 1) and colour with texture
 * height w = wtex(x); depth from the orthographic matrix. `normal_ok(x)`
 * restricts the normal/colour comparison. */
static void check_render(const meso_ref_image* img, const meso_ref_view* v, double H, double (*height)(double),
                         double (*slope)(double), double (*wtex)(double), int (*normal_ok)(double), render_check* rc)
{
    memset(rc, 0, sizeof(*rc));
    for (int y = 0; y < img->height; ++y)
        for (int x = 0; x < img->width; ++x) {
            const size_t i = (size_t)y * (size_t)img->width + (size_t)x;
            const double wx = -0.25 + 1.5 * (x + 0.5) / img->width, wy = -0.25 + 1.5 * (y + 0.5) / img->height;
            const int inside = wx > 0 && wx < 1 && wy > 0 && wy < 1;
            rc->coverage_wrong += inside != img->coverage[i];
            if (!inside || !img->coverage[i])
                continue;
            ++rc->covered;
            const double z = H * height(wx);
            rc->e_z = fmax(rc->e_z, fabs(img->hit[3 * i + 2] - z));
            rc->e_z = fmax(rc->e_z, fmax(fabs(img->hit[3 * i] - wx), fabs(img->hit[3 * i + 1] - wy)));
            /* Eye space z = z − 1, ndc = −2/(f−n)·z_eye − 1 = −(z − 1) − 1 = −z, depth = (1 − z)/2. */
            rc->e_depth = fmax(rc->e_depth, fabs(img->depth[i] - (1 - z) / 2));
            if (!normal_ok(wx))
                continue;
            double n[3] = {-H * slope(wx), 0, 1}, rgb[3];
            normalize(n);
            for (int c = 0; c < 3; ++c)
                rc->e_normal = fmax(rc->e_normal, fabs(img->normal[3 * i + c] - n[c]));
            expect_rgb(v, n, wtex(wx), rgb);
            for (int c = 0; c < 3; ++c)
                rc->e_rgb = fmax(rc->e_rgb, fabs(img->rgb[3 * i + c] - rgb[c]));
        }
}

static double g_const;
static double f_const(double x)
{
    (void)x;
    return g_const;
}
static double f_zero(double x)
{
    (void)x;
    return 0;
}
static int f_all(double x)
{
    (void)x;
    return 1;
}

/* The 8-texel ramp along s: texel i = (20 + 30 i)/255, bilinear, wrapping. */
static double ramp_texel(int i)
{
    return (20 + 30 * ((i % 8 + 8) % 8)) / 255.0;
}
static double f_ramp(double s)
{
    const double x = s * 8 - 0.5;
    const double fl = floor(x);
    const int i = (int)fl;
    return (1 - (x - fl)) * ramp_texel(i) + (x - fl) * ramp_texel(i + 1);
}
static double f_ramp_slope(double s)
{
    (void)s;
    return 30.0 / 255.0 * 8;
}
static int ramp_linear(double s)
{
    /* The central differences one texel apart stay within texels 0..7's
     * linear part (centres 1/16 .. 15/16). */
    return s - 1.0 / 8 > 1.0 / 16 + 1e-3 && s + 1.0 / 8 < 15.0 / 16 - 1e-3;
}

static void test_render(void)
{
    const double H = 0.2;
    const int N = 48;
    meso_ref_image img;
    render_check rc;

    /* Constant height field c = 128/255: the plane z = c H. */
    uint8_t flat[4 * 4];
    memset(flat, 128, sizeof(flat));
    meso_ref_shell s;
    CHECK(load_square(H, flat, 4, 4, &s));
    CHECK(s.tex.kind == 1 && s.vertex_count == 4 && s.triangle_count == 2 && s.layers == 1);
    meso_ref_view v = top_view(N);
    clock_t t0 = clock();
    CHECK(meso_ref_render(&s, &v, &img) == MESO_OK);
    const double secs = (double)(clock() - t0) / CLOCKS_PER_SEC;
    g_const = 128 / 255.0;
    check_render(&img, &v, H, f_const, f_zero, f_const, f_all, &rc);
    printf("render, constant height %.4f: %d px covered, %d coverage errors, |z| err %.3g, depth err %.3g, normal "
           "err %.3g, colour err %.3g (%.2f s CPU for %dx%d)\n",
           g_const, rc.covered, rc.coverage_wrong, rc.e_z, rc.e_depth, rc.e_normal, rc.e_rgb, secs, N, N);
    CHECK(rc.coverage_wrong == 0 && rc.covered > 0);
    CHECK(rc.e_z <= 1e-6 && rc.e_depth <= 1e-6 && rc.e_normal <= 1e-6 && rc.e_rgb <= 1e-6);
    /* Thread-count independence. */
    meso_ref_image img2;
    v.threads = 2;
    CHECK(meso_ref_render(&s, &v, &img2) == MESO_OK);
    const size_t np = (size_t)N * N;
    CHECK(!memcmp(img.rgb, img2.rgb, 12 * np) && !memcmp(img.depth, img2.depth, 4 * np) &&
          !memcmp(img.coverage, img2.coverage, np) && !memcmp(img.hit, img2.hit, 12 * np) &&
          !memcmp(img.normal, img2.normal, 12 * np));
    meso_ref_image_free(&img2);
    meso_ref_image_free(&img);
    meso_ref_shell_free(&s);

    /* A bilinear ramp along s (8 texels): z = H h(x), normal (−H h', 0, 1). */
    uint8_t ramp[8 * 2];
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 8; ++i)
            ramp[j * 8 + i] = (uint8_t)(20 + 30 * i);
    CHECK(load_square(H, ramp, 8, 2, &s));
    v = top_view(N);
    v.samples_per_prism = 256;
    CHECK(meso_ref_render(&s, &v, &img) == MESO_OK);
    check_render(&img, &v, H, f_ramp, f_ramp_slope, f_ramp, ramp_linear, &rc);
    printf("render, height ramp: %d px covered, %d coverage errors, |z| err %.3g, depth err %.3g, normal err %.3g, "
           "colour err %.3g\n",
           rc.covered, rc.coverage_wrong, rc.e_z, rc.e_depth, rc.e_normal, rc.e_rgb);
    CHECK(rc.coverage_wrong == 0 && rc.e_z <= 1e-6 && rc.e_depth <= 1e-6 && rc.e_normal <= 1e-5 &&
          rc.e_rgb <= 1e-5);
    meso_ref_image_free(&img);
    meso_ref_shell_free(&s);

    /* No texture function: every prism is solid and the hit is the offset
     * surface z = H (w = 1), normal +z. */
    CHECK(load_square(H, NULL, 0, 0, &s));
    CHECK(s.tex.kind == 0);
    v = top_view(N);
    CHECK(meso_ref_render(&s, &v, &img) == MESO_OK);
    g_const = 1.0;
    check_render(&img, &v, H, f_const, f_zero, f_const, f_all, &rc);
    printf("render, all solid: %d px covered, %d coverage errors, |z| err %.3g, normal err %.3g, colour err %.3g\n",
           rc.covered, rc.coverage_wrong, rc.e_z, rc.e_normal, rc.e_rgb);
    CHECK(rc.coverage_wrong == 0 && rc.e_z <= 1e-6 && rc.e_depth <= 1e-6 && rc.e_normal <= 1e-6 && rc.e_rgb <= 1e-6);
    meso_ref_image_free(&img);

    /* Curved, same flat square: parallel directors give Coons = 0, so the
     * offset surface is w̄ = w' = 3/4 at w = 1. Shading uses texture w = 1. */
    v.curved = 1;
    CHECK(meso_ref_render(&s, &v, &img) == MESO_OK);
    g_const = 0.75;
    check_render(&img, &v, H, f_const, f_zero, f_const, f_all, &rc);
    /* Colour uses w = 1, not 0.75: compare it separately. */
    double rgb1[3];
    const double nz[3] = {0, 0, 1};
    expect_rgb(&v, nz, 1.0, rgb1);
    double e_rgb1 = 0;
    for (size_t i = 0; i < np; ++i)
        if (img.coverage[i])
            for (int c = 0; c < 3; ++c)
                e_rgb1 = fmax(e_rgb1, fabs(img.rgb[3 * i + c] - rgb1[c]));
    printf("render, curved all solid: %d px covered, %d coverage errors, |z| err %.3g (plane z = 3/4 H), normal err "
           "%.3g, colour err %.3g\n",
           rc.covered, rc.coverage_wrong, rc.e_z, rc.e_normal, e_rgb1);
    CHECK(rc.coverage_wrong == 0 && rc.e_z <= 1e-6 && rc.e_depth <= 1e-6 && rc.e_normal <= 1e-6 && e_rgb1 <= 1e-6);
    meso_ref_image_free(&img);
    meso_ref_shell_free(&s);

    /* Loader refusals: a missing object, and a non-shell object. */
    size_t size = 0;
    void* buf = square_file(H, NULL, 0, 0, &size);
    meso_file* f = NULL;
    meso_error err;
    CHECK(meso_file_open_memory(buf, size, NULL, &f, &err) == MESO_OK);
    CHECK(meso_ref_shell_load(f, 7, &s, &err) == MESO_ERR_NOT_FOUND);
    meso_file_close(f);
    free(buf);
}

int main(void)
{
    test_smooth();
    test_curved();
    test_curved_range();
    test_texture();
    test_render();
    if (failures) {
        fprintf(stderr, "%d check(s) failed\n", failures);
        return 1;
    }
    printf("all checks passed\n");
    return 0;
}
