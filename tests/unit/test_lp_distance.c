/* test_lp_distance.c — the Lp-averaged distance field (bake/lp_distance.c)
 * against independent expectations: brute-force quadrature, finite
 * differences, exact summation, the symmetry of a sphere and a torus, and the
 * far-field limit |∇d_p| → 1. Timings are printed, not asserted. */
#include "meso_clock.h"
#include "test_util.h"

#include <pthread.h>
#include <string.h>
#include <time.h>

#include "adapters.h"
#include "test_mesh.h"
#include "lp_distance.h"

/* >>helpers ---------------------------------------------------------------- */


static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double norm(const double a[3])
{
    return sqrt(dot(a, a));
}

static double angle_deg(const double a[3], const double b[3])
{
    double c = dot(a, b) / (norm(a) * norm(b));
    c = c > 1.0 ? 1.0 : (c < -1.0 ? -1.0 : c);
    return acos(c) * 180.0 / M_PI;
}

static void rng_unit(uint64_t* s, double v[3])
{
    do {
        for (int k = 0; k < 3; ++k)
            v[k] = test_rng_uniform(s, -1.0, 1.0);
    } while (dot(v, v) > 1.0 || dot(v, v) < 1e-4);
    double l = norm(v);
    for (int k = 0; k < 3; ++k)
        v[k] /= l;
}

static meso_lp_field* make_field(const meso_mesh* m, const meso_lp_options* o)
{
    meso_lp_field* f = NULL;
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_result r = meso_lp_field_create(m->positions, m->vertex_count, m->indices, m->triangle_count, o, &f, &err);
    if (r != MESO_OK)
        fprintf(stderr, "    field: %s\n", err.message);
    assert(r == MESO_OK && f);
    return f;
}

/* >>brute-force reference quadrature ----------------------------------------
 * Independent of the library: recursive 4-way midpoint subdivision with the
 * 3-point edge-midpoint rule (degree 2), Richardson-corrected (error O(s³),
 * so fine + (fine − coarse)/7), refined until each element agrees to `rel`
 * relative to its own value. out = {∫r^−p, ∫(x−y)r^(−p−2) (3), ∫r^(−p−1)}. */

static void bf_rule(const double* v, const double x[3], double p, double out[5])
{
    double e1[3], e2[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = v[3 + k] - v[k];
        e2[k] = v[6 + k] - v[k];
    }
    double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double w = 0.5 * norm(cr) / 3.0;
    memset(out, 0, 5 * sizeof(double));
    for (int e = 0; e < 3; ++e) {
        const double* a = v + 3 * e;
        const double* b = v + 3 * ((e + 1) % 3);
        double R[3];
        for (int k = 0; k < 3; ++k)
            R[k] = x[k] - 0.5 * (a[k] + b[k]);
        double r = norm(R), kp = pow(r, -p);
        out[0] += w * kp;
        for (int k = 0; k < 3; ++k)
            out[1 + k] += w * kp / (r * r) * R[k];
        out[4] += w * kp / r;
    }
}

static void bf_rec(const double* v, const double x[3], double p, double rel, const double coarse[5], int depth,
                   double acc[5])
{
    double m[9], ch[4][9], cv[4][5], fine[5] = {0, 0, 0, 0, 0};
    for (int k = 0; k < 3; ++k) {
        m[k] = 0.5 * (v[k] + v[3 + k]);
        m[3 + k] = 0.5 * (v[3 + k] + v[6 + k]);
        m[6 + k] = 0.5 * (v[6 + k] + v[k]);
    }
    const double* tri[4][3] = {{v, m, m + 6}, {m, v + 3, m + 3}, {m + 6, m + 3, v + 6}, {m, m + 3, m + 6}};
    for (int i = 0; i < 4; ++i) {
        for (int c = 0; c < 3; ++c)
            memcpy(ch[i] + 3 * c, tri[i][c], 3 * sizeof(double));
        bf_rule(ch[i], x, p, cv[i]);
        for (int k = 0; k < 5; ++k)
            fine[k] += cv[i][k];
    }
    int ok = fabs(fine[0] - coarse[0]) <= rel * fine[0];
    for (int k = 1; k < 4; ++k)
        ok = ok && fabs(fine[k] - coarse[k]) <= rel * fine[4];
    if (ok || depth >= 40) {
        for (int k = 0; k < 5; ++k)
            acc[k] += fine[k] + (fine[k] - coarse[k]) / 7.0;
        return;
    }
    for (int i = 0; i < 4; ++i)
        bf_rec(ch[i], x, p, rel, cv[i], depth + 1, acc);
}

static void brute_force(const double* v, const double x[3], double p, double rel, double out[5])
{
    double coarse[5];
    bf_rule(v, x, p, coarse);
    memset(out, 0, 5 * sizeof(double));
    bf_rec(v, x, p, rel, coarse, 0, out);
}

/* A random, not too skinny triangle in [−1, 1]³. */
static void random_triangle(uint64_t* s, double v[9], double n[3], double* area)
{
    for (;;) {
        for (int k = 0; k < 9; ++k)
            v[k] = test_rng_uniform(s, -1.0, 1.0);
        double e1[3], e2[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = v[3 + k] - v[k];
            e2[k] = v[6 + k] - v[k];
        }
        double cr[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                        e1[0] * e2[1] - e1[1] * e2[0]};
        double l2 = dot(e1, e1) + dot(e2, e2);
        *area = 0.5 * norm(cr);
        if (*area > 0.15 * l2 * 0.5) {
            for (int k = 0; k < 3; ++k)
                n[k] = cr[k] / norm(cr);
            return;
        }
    }
}

enum { PT_FAR, PT_ABOVE, PT_SIDE, PT_PLANE, PT_KINDS };
static const char* const pt_name[PT_KINDS] = {"far", "above", "side", "near-plane"};

/* A point of the given kind relative to triangle v; *clear is a lower bound
 * of its distance to the triangle (for finite-difference steps). */
static void random_point(uint64_t* s, int kind, const double v[9], const double n[3], double x[3], double* clear)
{
    double g[3];
    for (int k = 0; k < 3; ++k)
        g[k] = (v[k] + v[3 + k] + v[6 + k]) / 3.0;
    if (kind == PT_FAR) {
        double dir[3], r = test_rng_uniform(s, 4.0, 40.0);
        rng_unit(s, dir);
        for (int k = 0; k < 3; ++k)
            x[k] = g[k] + r * dir[k];
        *clear = r - 2.0 * sqrt(3.0);
        return;
    }
    if (kind == PT_ABOVE) { /* over the interior, 1e-3 .. 1e-1 off the plane */
        double b0 = test_rng_uniform(s, 0.05, 0.9), b1 = test_rng_uniform(s, 0.05, 0.95 - b0);
        double h = pow(10.0, test_rng_uniform(s, -3.0, -1.0)) * (test_rng_next(s) & 1 ? 1.0 : -1.0);
        for (int k = 0; k < 3; ++k)
            x[k] = b0 * v[k] + b1 * v[3 + k] + (1.0 - b0 - b1) * v[6 + k] + h * n[k];
        *clear = fabs(h);
        return;
    }
    /* Beyond an edge: from the edge midpoint outwards in the plane by
     * `out` (≥ 0.05), then off the plane by h (side: up to 0.5, near-plane:
     * 0 or 1e-8 .. 1e-2). */
    int e = (int)(test_rng_next(s) % 3);
    const double* a = v + 3 * e;
    const double* b = v + 3 * ((e + 1) % 3);
    double t = test_rng_uniform(s, 0.1, 0.9), mid[3], ed[3], o[3];
    for (int k = 0; k < 3; ++k) {
        mid[k] = a[k] + t * (b[k] - a[k]);
        ed[k] = b[k] - a[k];
    }
    /* in-plane outward direction: n × edge for counter-clockwise (a, b, c) */
    o[0] = ed[1] * n[2] - ed[2] * n[1];
    o[1] = ed[2] * n[0] - ed[0] * n[2];
    o[2] = ed[0] * n[1] - ed[1] * n[0];
    double lo = norm(o);
    double out = test_rng_uniform(s, 0.05, 1.0);
    double h = kind == PT_SIDE ? test_rng_uniform(s, -0.5, 0.5)
                               : (test_rng_next(s) % 4 == 0 ? 0.0 : pow(10.0, test_rng_uniform(s, -8.0, -2.0)));
    for (int k = 0; k < 3; ++k)
        x[k] = mid[k] + out * o[k] / lo + h * n[k];
    /* The perpendicular foot is on the edge, but the triangle may still be
     * closer through another edge near an obtuse corner: check against the
     * vertices and use a conservative clearance. */
    double c = sqrt(out * out + h * h);
    for (int i = 0; i < 3; ++i) {
        double d[3] = {x[0] - v[3 * i], x[1] - v[3 * i + 1], x[2] - v[3 * i + 2]};
        c = fmin(c, norm(d));
    }
    *clear = 0.5 * c;
}

/* >>1. triangle integral vs brute force ------------------------------------ */

static void test_triangle_vs_brute_force(void)
{
    uint64_t s = 0x1234567ULL;
    double maxI[PT_KINDS] = {0}, maxJ[PT_KINDS] = {0}, maxQ[PT_KINDS] = {0}, maxQ4[PT_KINDS] = {0};
    int npts = 0;
    for (int tcount = 0; tcount < 8; ++tcount) {
        double v[9], n[3], area;
        random_triangle(&s, v, n, &area);
        for (int kind = 0; kind < PT_KINDS; ++kind)
            for (int rep = 0; rep < 3; ++rep) {
                double x[3], clear, ref[5], j[3];
                random_point(&s, kind, v, n, x, &clear);
                brute_force(v, x, 3.0, kind == PT_FAR ? 1e-7 : 1e-5, ref);
                double I = meso_lp_triangle_p3(v, v + 3, v + 6, x, j);
                assert(isfinite(I) && I > 0.0);
                double dJ = 0.0;
                for (int k = 0; k < 3; ++k)
                    dJ = fmax(dJ, fabs(j[k] - ref[1 + k]));
                maxI[kind] = fmax(maxI[kind], fabs(I - ref[0]) / ref[0]);
                maxJ[kind] = fmax(maxJ[kind], dJ / ref[4]);
                /* The library's own adaptive quadrature (the p != 3 path) at
                 * p = 3 against the closed form... */
                double jq[3];
                double Iq = meso_lp_triangle_quad(v, v + 3, v + 6, x, 3.0, 0.0, jq);
                double dq = fabs(Iq - I) / I;
                for (int k = 0; k < 3; ++k)
                    dq = fmax(dq, fabs(jq[k] - j[k]) / ref[4]);
                maxQ[kind] = fmax(maxQ[kind], dq);
                /* ...and at p = 4 against brute force. */
                double ref4[5];
                brute_force(v, x, 4.0, kind == PT_FAR ? 1e-7 : 1e-5, ref4);
                double I4 = meso_lp_triangle_quad(v, v + 3, v + 6, x, 4.0, 0.0, jq);
                double d4 = fabs(I4 - ref4[0]) / ref4[0];
                for (int k = 0; k < 3; ++k)
                    d4 = fmax(d4, fabs(jq[k] - ref4[1 + k]) / ref4[4]);
                maxQ4[kind] = fmax(maxQ4[kind], d4);
                npts++;
            }
    }
    fprintf(stderr, "    %d points; max relative error (J: |ΔJ|_inf / ∫r^(-p-1)):\n", npts);
    for (int kind = 0; kind < PT_KINDS; ++kind)
        fprintf(stderr, "      %-10s  p3 I %.1e  J %.1e | quad p3 vs closed %.1e | quad p4 vs brute %.1e\n",
                pt_name[kind], maxI[kind], maxJ[kind], maxQ[kind], maxQ4[kind]);
    assert(maxI[PT_FAR] < 1e-6 && maxJ[PT_FAR] < 1e-6);
    for (int kind = 0; kind < PT_KINDS; ++kind) {
        /* measured ≤ 1.2e-8 (mostly the brute force's own error) */
        assert(maxI[kind] < 1e-6 && maxJ[kind] < 1e-6);
        assert(maxQ[kind] < 1e-8); /* two independent derivations (default tolerance) */
        assert(maxQ4[kind] < 1e-6);
    }

    /* Exactly in the plane outside the triangle: the 0/0 limit is finite and
     * continuous with points just off the plane. */
    double v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    double x0[3] = {0.3, -0.2, 0.0}, x1[3] = {0.3, -0.2, 1e-9}, ref[5];
    double I0 = meso_lp_triangle_p3(v, v + 3, v + 6, x0, NULL);
    double I1 = meso_lp_triangle_p3(v, v + 3, v + 6, x1, NULL);
    brute_force(v, x0, 3.0, 1e-8, ref);
    fprintf(stderr, "    in-plane: closed %.12g, 1e-9 above %.12g, brute force %.12g\n", I0, I1, ref[0]);
    assert(fabs(I0 - ref[0]) < 1e-6 * ref[0] && fabs(I1 - I0) < 1e-8 * I0);
    /* On the triangle: +∞; degenerate triangle: 0. */
    double on[3] = {0.2, 0.2, 0.0}, j[3];
    assert(isinf(meso_lp_triangle_p3(v, v + 3, v + 6, on, j)) && j[0] == 0.0);
    assert(isinf(meso_lp_triangle_quad(v, v + 3, v + 6, on, 4.0, 0.0, j)));
    double edge[3] = {0.5, 0.0, 0.0};
    assert(isinf(meso_lp_triangle_p3(v, v + 3, v + 6, edge, NULL)));
    double flat[9] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    assert(meso_lp_triangle_p3(flat, flat + 3, flat + 6, x1, j) == 0.0);
}

/* >>2. gradient vs finite differences -------------------------------------- */

static void test_gradient_fd(void)
{
    uint64_t s = 0xfeedULL;
    double maxe3 = 0.0, maxe4 = 0.0;
    for (int tcount = 0; tcount < 20; ++tcount) {
        double v[9], n[3], area;
        random_triangle(&s, v, n, &area);
        for (int kind = 0; kind < PT_KINDS; ++kind) {
            double x[3], clear, j3[3], j4[3];
            random_point(&s, kind, v, n, x, &clear);
            if (kind == PT_PLANE)
                clear = fmax(clear, 1e-3); /* FD across the plane is smooth outside T */
            meso_lp_triangle_p3(v, v + 3, v + 6, x, j3);
            meso_lp_triangle_quad(v, v + 3, v + 6, x, 4.0, 1e-12, j4);
            double step = 1e-4 * clear, fd3[3], fd4[3];
            for (int k = 0; k < 3; ++k) {
                double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]};
                xp[k] += step;
                xm[k] -= step;
                /* J = −(1/p) ∇ ∫ r^−p */
                fd3[k] = -(meso_lp_triangle_p3(v, v + 3, v + 6, xp, NULL) -
                           meso_lp_triangle_p3(v, v + 3, v + 6, xm, NULL)) / (2.0 * step) / 3.0;
                fd4[k] = -(meso_lp_triangle_quad(v, v + 3, v + 6, xp, 4.0, 1e-13, NULL) -
                           meso_lp_triangle_quad(v, v + 3, v + 6, xm, 4.0, 1e-13, NULL)) / (2.0 * step) / 4.0;
            }
            double d3[3] = {fd3[0] - j3[0], fd3[1] - j3[1], fd3[2] - j3[2]};
            double d4[3] = {fd4[0] - j4[0], fd4[1] - j4[1], fd4[2] - j4[2]};
            maxe3 = fmax(maxe3, norm(d3) / norm(j3));
            maxe4 = fmax(maxe4, norm(d4) / norm(j4));
        }
    }
    fprintf(stderr, "    triangle: max |J − FD|/|J|: p3 closed form %.1e, p4 quadrature %.1e\n", maxe3, maxe4);
    assert(maxe3 < 1e-6 && maxe4 < 1e-5);

    meso_mesh m = {0};
    if (!test_load_mesh(test_data("torus.obj"), &m))
        return;
    double maxm[2] = {0, 0};
    for (int pi = 0; pi < 2; ++pi) {
        meso_lp_options o = {.p = pi == 0 ? 3.0 : 4.0, .quad_tol = 1e-12};
        meso_lp_field* f = make_field(&m, &o);
        for (int i = 0; i < (pi == 0 ? 12 : 6); ++i) {
            /* Around the tube (R 1, r 0.25, axis y), 0.05 .. 0.6 from it. */
            double phi = test_rng_uniform(&s, 0, 2 * M_PI), psi = test_rng_uniform(&s, 0, 2 * M_PI);
            double rho = test_rng_uniform(&s, 0.3, 0.85) * (i % 3 == 0 ? 0.0 : 1.0) +
                         (i % 3 == 0 ? test_rng_uniform(&s, 0.05, 0.18) : 0.0);
            double x[3] = {(1 + rho * cos(psi)) * cos(phi), rho * sin(psi), (1 + rho * cos(psi)) * sin(phi)};
            double d, g[3], fd[3], step = 1e-5;
            assert(meso_lp_eval_exact(f, x, &d, g) == MESO_OK);
            for (int k = 0; k < 3; ++k) {
                double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]}, dp, dm;
                xp[k] += step;
                xm[k] -= step;
                assert(meso_lp_eval_exact(f, xp, &dp, NULL) == MESO_OK);
                assert(meso_lp_eval_exact(f, xm, &dm, NULL) == MESO_OK);
                fd[k] = (dp - dm) / (2 * step);
            }
            double dd[3] = {fd[0] - g[0], fd[1] - g[1], fd[2] - g[2]};
            maxm[pi] = fmax(maxm[pi], norm(dd) / norm(g));
        }
        meso_lp_field_destroy(f);
    }
    fprintf(stderr, "    torus d_p: max |∇d − FD|/|∇d|: p3 %.1e, p4 %.1e\n", maxm[0], maxm[1]);
    assert(maxm[0] < 1e-5 && maxm[1] < 1e-5);
    meso_mesh_free(&m);
}

/* >>3. Barnes–Hut vs exact -------------------------------------------------- */

typedef struct bh_err {
    double max_g, rms_g, max_d;
} bh_err;

static bh_err bh_error(const meso_lp_field* f, const double* pts, int n, double theta, meso_lp_stats* st)
{
    bh_err e = {0, 0, 0};
    for (int i = 0; i < n; ++i) {
        double d0, g0[3], d1, g1[3];
        assert(meso_lp_eval_exact(f, pts + 3 * i, &d0, g0) == MESO_OK);
        assert(meso_lp_eval_ex(f, pts + 3 * i, theta, 0.0, &d1, g1, st) == MESO_OK);
        double dg[3] = {g1[0] - g0[0], g1[1] - g0[1], g1[2] - g0[2]};
        double rel = norm(dg) / norm(g0);
        e.max_g = fmax(e.max_g, rel);
        e.rms_g += rel * rel;
        e.max_d = fmax(e.max_d, fabs(d1 - d0) / d0);
    }
    e.rms_g = sqrt(e.rms_g / n);
    return e;
}

/* Points 0.02 .. 1 away from a unit sphere / the torus tube, both sides. */
static void shell_points(uint64_t* s, int torus, double* pts, int n)
{
    for (int i = 0; i < n; ++i) {
        double* x = pts + 3 * i;
        double off = pow(10.0, test_rng_uniform(s, log10(0.02), 0.0)) * (i & 1 ? 1.0 : -1.0);
        if (!torus) {
            double dir[3];
            rng_unit(s, dir);
            double r = 1.0 + (off < 0 ? fmax(off, -0.7) : off);
            for (int k = 0; k < 3; ++k)
                x[k] = r * dir[k];
        } else {
            double phi = test_rng_uniform(s, 0, 2 * M_PI), psi = test_rng_uniform(s, 0, 2 * M_PI);
            double rho = 0.25 + (off < 0 ? fmax(off, -0.2) : off);
            x[0] = (1 + rho * cos(psi)) * cos(phi);
            x[1] = rho * sin(psi);
            x[2] = (1 + rho * cos(psi)) * sin(phi);
        }
    }
}

static void test_barnes_hut(void)
{
    static const char* const names[2] = {"sphere.obj", "torus.obj"};
    static const double thetas[5] = {0.8, 0.5, 0.3, 0.2, 0.1};
    enum { NPTS = 150 };
    static double pts[3 * NPTS];
    for (int mi = 0; mi < 2; ++mi) {
        meso_mesh m = {0};
        if (!test_load_mesh(test_data(names[mi]), &m))
            return;
        uint64_t s = 0xb4b4ULL + (uint64_t)mi;
        shell_points(&s, mi, pts, NPTS);
        for (int order = 1; order <= 2; ++order) {
            meso_lp_options o = {.order = order};
            meso_lp_field* f = make_field(&m, &o);
            double prev = INFINITY;
            for (int ti = 0; ti < 5; ++ti) {
                meso_lp_stats st = {0};
                bh_err e = bh_error(f, pts, NPTS, thetas[ti], &st);
                fprintf(stderr,
                        "    %-10s order %d theta %.1f: gradient rel err max %.2e rms %.2e, d rel err max %.2e;"
                        " per point %.0f exact + %.0f far tris, %.0f multipoles (of %u tris)\n",
                        names[mi], order, thetas[ti], e.max_g, e.rms_g, e.max_d, (double)st.exact_triangles / NPTS,
                        (double)st.far_triangles / NPTS, (double)st.multipoles / NPTS, m.triangle_count);
                assert(e.rms_g < prev); /* error falls as theta falls */
                prev = e.rms_g;
                /* Bounds: the measured maxima (sphere / torus, order 2:
                 * θ 0.5 1.9e-2 / 3.6e-2, 0.3 1.4e-3 / 3.0e-3, 0.2 3.0e-4 /
                 * 5.1e-4, 0.1 1.1e-5 / 1.2e-5; order 1: θ 0.5 0.10 / 0.12,
                 * 0.2 2.1e-2 / 1.8e-2) with ~3x margin. The r^−(p+2) kernel
                 * is steeper than gravity's 1/r², hence the small θ. */
                static const double bound2[5] = {1.0, 0.1, 1e-2, 2e-3, 1e-4};
                static const double bound1[5] = {1.0, 0.3, 0.1, 0.05, 2e-2};
                assert(e.max_g < (order == 2 ? bound2[ti] : bound1[ti]));
            }
            meso_lp_field_destroy(f);
        }
        /* near_radius: every triangle within it is exact, so a radius
         * covering the mesh reproduces exact summation bit for bit. */
        meso_lp_field* f = make_field(&m, NULL);
        for (int i = 0; i < 10; ++i) {
            double d0, g0[3], d1, g1[3];
            assert(meso_lp_eval_exact(f, pts + 3 * i, &d0, g0) == MESO_OK);
            meso_lp_stats st = {0};
            assert(meso_lp_eval_ex(f, pts + 3 * i, 0.5, 100.0, &d1, g1, &st) == MESO_OK);
            assert(st.multipoles == 0 && st.far_triangles == 0 && st.exact_triangles == m.triangle_count);
            assert(fabs(d1 - d0) <= 1e-12 * d0 && fabs(g1[0] - g0[0]) <= 1e-12 && fabs(g1[2] - g0[2]) <= 1e-12);
        }
        meso_lp_field_destroy(f);
        meso_mesh_free(&m);
    }
}

/* >>4. the field of a sphere and a torus ------------------------------------- */

static void test_symmetric_fields(void)
{
    meso_mesh m = {0};
    if (!test_load_mesh(test_data("sphere.obj"), &m))
        return;
    uint64_t s = 0x5feeULL;
    for (int pi = 0; pi < 2; ++pi) {
        meso_lp_options o = {.p = pi == 0 ? 3.0 : 4.0};
        meso_lp_field* f = make_field(&m, &o);
        double max_out = 0.0, max_in = 0.0;
        for (int i = 0; i < 60; ++i) {
            double dir[3], x[3], d, g[3], in = i & 1;
            rng_unit(&s, dir);
            double r = in ? test_rng_uniform(&s, 0.5, 0.9) : test_rng_uniform(&s, 1.1, 3.0);
            for (int k = 0; k < 3; ++k)
                x[k] = r * dir[k];
            assert(meso_lp_eval(f, x, &d, g) == MESO_OK);
            if (in) { /* d_p grows away from the surface: towards the centre */
                double mdir[3] = {-dir[0], -dir[1], -dir[2]};
                max_in = fmax(max_in, angle_deg(g, mdir));
            } else {
                max_out = fmax(max_out, angle_deg(g, dir));
            }
        }
        fprintf(stderr, "    sphere p%.0f: max angle to radial outside (1.1..3) %.3f deg, to centre inside (0.5..0.9) %.3f deg\n",
                o.p, max_out, max_in);
        assert(max_out < 1.0 && max_in < 1.0);
        meso_lp_field_destroy(f);
    }
    meso_mesh_free(&m);

    if (!test_load_mesh(test_data("torus.obj"), &m))
        return;
    meso_lp_field* f = make_field(&m, NULL);
    double max_out = 0.0, max_in = 0.0;
    for (int i = 0; i < 80; ++i) {
        double phi = test_rng_uniform(&s, 0, 2 * M_PI), psi = test_rng_uniform(&s, 0, 2 * M_PI);
        int in = i & 1;
        double rho = in ? test_rng_uniform(&s, 0.15, 0.2) : test_rng_uniform(&s, 0.3, 0.35);
        double nrm[3] = {cos(psi) * cos(phi), sin(psi), cos(psi) * sin(phi)};
        double x[3] = {(1 + rho * cos(psi)) * cos(phi), rho * sin(psi), (1 + rho * cos(psi)) * sin(phi)};
        double d, g[3];
        assert(meso_lp_eval(f, x, &d, g) == MESO_OK);
        if (in) {
            double mn[3] = {-nrm[0], -nrm[1], -nrm[2]};
            max_in = fmax(max_in, angle_deg(g, mn));
        } else {
            max_out = fmax(max_out, angle_deg(g, nrm));
        }
    }
    fprintf(stderr, "    torus p3: max angle to tube normal: outside (0.05..0.1 off) %.2f deg, inside (0.05..0.1 in) %.2f deg\n",
            max_out, max_in);
    assert(max_out < 3.0 && max_in < 5.0);
    meso_lp_field_destroy(f);
    meso_mesh_free(&m);
}

/* >>5. far field ----------------------------------------------------------- */

static void test_far_field(void)
{
    meso_mesh m = {0};
    if (!test_load_mesh(test_data("torus.obj"), &m))
        return;
    uint64_t s = 0xfa4ULL;
    for (int pi = 0; pi < 2; ++pi) {
        meso_lp_options o = {.p = pi == 0 ? 3.0 : 5.0};
        meso_lp_field* f = make_field(&m, &o);
        double lo[3], hi[3], size = meso_mesh_bounds(&m, lo, hi);
        double dev[2] = {0, 0}, ddev[2] = {0, 0};
        for (int i = 0; i < 40; ++i) {
            int far = i & 1;
            double dir[3], x[3], d, g[3];
            rng_unit(&s, dir);
            double r = (far ? 100.0 : 10.0) * size;
            for (int k = 0; k < 3; ++k)
                x[k] = r * dir[k];
            assert(meso_lp_eval(f, x, &d, g) == MESO_OK);
            dev[far] = fmax(dev[far], fabs(norm(g) - 1.0));
            ddev[far] = fmax(ddev[far], fabs(d / r - 1.0));
        }
        fprintf(stderr, "    torus p%.0f: max ||grad|-1| at 10x size %.2e, at 100x %.2e; max |d/|x|-1| %.2e, %.2e\n",
                o.p, dev[0], dev[1], ddev[0], ddev[1]);
        assert(dev[1] < 1e-2 && dev[1] < dev[0] && ddev[1] < 1e-2);
        meso_lp_field_destroy(f);
    }
    meso_mesh_free(&m);
}

/* >>regions (lp_distance.h): a tree built for a box gives, at points in
 * the box, the whole tree's evaluation bit for bit (d, gradient and the
 * work counters: the same clusters in the same order), and at points
 * outside it a correct field (against exact summation, as close as the
 * whole tree is, give or take), by summing the unsplit clusters triangle
 * by triangle (more triangles than the whole tree touches). */
static void test_region(void)
{
    meso_mesh m = {0};
    if (!test_load_mesh(test_data("torus.obj"), &m))
        return;
    double lo[3], hi[3];
    const double size = meso_mesh_bounds(&m, lo, hi);
    const float* v0 = m.positions + 3 * (size_t)(m.vertex_count / 3);
    const double box[6] = {v0[0] - 0.08 * size, v0[1] - 0.08 * size, v0[2] - 0.08 * size,
                           v0[0] + 0.08 * size, v0[1] + 0.08 * size, v0[2] + 0.08 * size};
    meso_lp_options whole_opt = {.theta = 0.5}, region_opt = {.theta = 0.5, .region = box};
    meso_lp_field* whole = make_field(&m, &whole_opt);
    meso_lp_field* part = make_field(&m, &region_opt);
    uint64_t s = 0x4e610aULL;
    int inside = 0, outside = 0, unsplit = 0;
    double worst_whole = 0, worst_part = 0;
    for (int i = 0; i < 400; ++i) {
        double x[3], dw, dp, gw[3], gp[3];
        const int in = i % 2 == 0;
        for (int k = 0; k < 3; ++k)
            x[k] = in ? test_rng_uniform(&s, box[k], box[3 + k]) : test_rng_uniform(&s, lo[k], hi[k]);
        const int in_box = x[0] >= box[0] && x[0] <= box[3] && x[1] >= box[1] && x[1] <= box[4] &&
                           x[2] >= box[2] && x[2] <= box[5];
        meso_lp_stats sw = {0}, sp = {0};
        if (meso_lp_eval_ex(whole, x, 0.5, 0.0, &dw, gw, &sw) != MESO_OK)
            continue; /* on the surface */
        const uint64_t opened = meso_lp_field_unsplit_opened(part);
        assert(meso_lp_eval_ex(part, x, 0.5, 0.0, &dp, gp, &sp) == MESO_OK);
        const uint64_t opened_now = meso_lp_field_unsplit_opened(part) - opened;
        /* the counter says whether this evaluation left the whole tree's path */
        assert((opened_now > 0) == (sp.exact_triangles + sp.far_triangles > sw.exact_triangles + sw.far_triangles));
        if (in_box) {
            ++inside;
            assert(opened_now == 0);
            assert(memcmp(&dw, &dp, sizeof dw) == 0 && memcmp(gw, gp, sizeof gw) == 0);
            assert(sw.nodes_visited == sp.nodes_visited && sw.multipoles == sp.multipoles &&
                   sw.exact_triangles == sp.exact_triangles && sw.far_triangles == sp.far_triangles);
        } else {
            ++outside;
            double de, ge[3];
            assert(meso_lp_eval_exact(whole, x, &de, ge) == MESO_OK);
            worst_whole = fmax(worst_whole, fabs(dw / de - 1));
            worst_part = fmax(worst_part, fabs(dp / de - 1));
            assert(angle_deg(gp, ge) < 2.0);
            assert(sp.exact_triangles + sp.far_triangles >= sw.exact_triangles + sw.far_triangles);
            unsplit += sp.exact_triangles + sp.far_triangles > sw.exact_triangles + sw.far_triangles;
        }
    }
    fprintf(stderr, "    torus, box of 0.16 x size: %d points inside (same bits), %d outside (%d met an unsplit "
                    "cluster): max |d/d_exact - 1| %.2e (whole tree %.2e)\n", inside, outside, unsplit, worst_part,
            worst_whole);
    assert(inside > 150 && outside > 150 && unsplit > outside / 2);
    assert(meso_lp_field_unsplit_opened(whole) == 0 && meso_lp_field_unsplit_opened(part) >= (uint64_t)unsplit);
    assert(worst_part < 1e-2 && worst_part <= 2 * worst_whole + 1e-6);
    meso_lp_field_destroy(whole);
    meso_lp_field_destroy(part);
    meso_mesh_free(&m);
}

/* >>6. bad input ------------------------------------------------------------ */

/* >>localisation: meso_lp_eval_local over a sphere A and a far copy B
 * (100 units away, entirely beyond the cut-off) is the field of A alone up
 * to the area normalisation: with the same I and J, d scales by
 * (A_total / A_A)^(1/3) (d = (I/A)^(−1/p), p = 3) and so does ∇d = d J / I.
 * Exact summation must agree to rounding; Barnes–Hut (different trees) to
 * its error. And a cut-off that takes in all of A but not B must differ
 * from the whole surface. */
static void test_localised(void)
{
    meso_mesh a;
    if (!test_load_mesh(test_data("sphere.obj"), &a))
        assert(0 && "sphere.obj");
    const uint32_t nv = a.vertex_count, nt = a.triangle_count;
    float* pos = malloc(sizeof(float) * 6 * nv);
    uint32_t* idx = malloc(sizeof(uint32_t) * 6 * nt);
    assert(pos && idx);
    for (uint32_t i = 0; i < 3 * nv; ++i) {
        pos[i] = a.positions[i];
        pos[3 * nv + i] = a.positions[i] + (i % 3 == 0 ? 100.0f : 0.0f);
    }
    for (uint32_t i = 0; i < 3 * nt; ++i) {
        idx[i] = a.indices[i];
        idx[3 * nt + i] = a.indices[i] + nv;
    }
    meso_mesh both = a;
    both.positions = pos, both.indices = idx, both.vertex_count = 2 * nv, both.triangle_count = 2 * nt;
    const meso_lp_options o = {.p = 3};
    meso_lp_field* fa = make_field(&a, &o);
    meso_lp_field* fb = make_field(&both, &o);
    const double scale = cbrt(meso_lp_field_area(fb) / meso_lp_field_area(fa));
    assert(fabs(scale - cbrt(2.0)) < 1e-4); /* B in floats 100 units out: areas to ~1e-6 */
    const double pts[][3] = {{1.3, 0.2, -0.1}, {0.1, -1.6, 0.4}, {-0.5, 0.5, 0.4}, {2.5, 2.0, 1.0}};
    for (size_t i = 0; i < sizeof(pts) / sizeof(pts[0]); ++i)
        for (int bh = 0; bh < 2; ++bh) {
            const double theta = bh ? 0.5 : 0.0, tol = bh ? 2e-2 : 1e-10;
            double da, ga[3], dl, gl[3], dw, gw[3];
            assert(meso_lp_eval_ex(fa, pts[i], theta, 0.0, &da, ga, NULL) == MESO_OK);
            assert(meso_lp_eval_local(fb, pts[i], theta, 10.0, &dl, gl, NULL) == MESO_OK);
            assert(meso_lp_eval_ex(fb, pts[i], theta, 0.0, &dw, gw, NULL) == MESO_OK);
            assert(fabs(dl - scale * da) <= tol * dl);
            for (int k = 0; k < 3; ++k)
                assert(fabs(gl[k] - scale * ga[k]) <= tol * norm(gl));
            /* B adds ~area/100^3 to I: the whole-surface d is smaller */
            if (!bh)
                assert(dw < dl);
        }
    double d, g[3];
    assert(meso_lp_eval_local(fb, pts[0], 0.5, 0.0, &d, g, NULL) == MESO_ERR_INVALID_ARG);
    const double lonely[3] = {50.0, 0.0, 0.0}; /* no triangle within 1 */
    assert(meso_lp_eval_local(fb, lonely, 0.5, 1.0, &d, g, NULL) == MESO_ERR_INVALID_ARG);
    meso_lp_field_destroy(fa);
    meso_lp_field_destroy(fb);
    free(pos);
    free(idx);
    meso_mesh_free(&a);
}

static void expect_error(const float* pos, uint32_t nv, const uint32_t* idx, uint32_t nt, const meso_lp_options* o,
                         const char* needle)
{
    meso_error err;
    memset(&err, 0, sizeof(err));
    meso_lp_field* f = (meso_lp_field*)&err; /* must be reset to NULL */
    meso_result r = meso_lp_field_create(pos, nv, idx, nt, o, &f, &err);
    fprintf(stderr, "    -> %s\n", err.message);
    assert(r == MESO_ERR_INVALID_ARG && f == NULL && err.result == r);
    assert(strstr(err.message, needle) != NULL);
}

static void test_bad_input(void)
{
    float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
    uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    pos[4] = NAN;
    expect_error(pos, 4, idx, 2, NULL, "non-finite");
    pos[4] = 0.0f;
    uint32_t bad_idx[6] = {0, 1, 2, 0, 2, 4};
    expect_error(pos, 4, bad_idx, 2, NULL, "vertex 4");
    float line[9] = {0, 0, 0, 1, 1, 1, 2, 2, 2};
    expect_error(line, 3, idx, 1, NULL, "zero total area");
    float same[9] = {1, 1, 1, 1, 1, 1, 1, 1, 1};
    expect_error(same, 3, idx, 1, NULL, "zero total area");
    expect_error(pos, 4, idx, 0, NULL, "empty");
    expect_error(NULL, 4, idx, 2, NULL, "NULL");
    expect_error(pos, 4, idx, 2, &(meso_lp_options){.p = 1.0}, "p = 1");
    expect_error(pos, 4, idx, 2, &(meso_lp_options){.theta = -1.0}, "theta");
    expect_error(pos, 4, idx, 2, &(meso_lp_options){.near_radius = NAN}, "near_radius");
    const double inverted_box[6] = {0, 0, 1, 1, 1, 0}, nan_box[6] = {0, 0, 0, NAN, 1, 1};
    expect_error(pos, 4, idx, 2, &(meso_lp_options){.region = inverted_box}, "region axis 2");
    expect_error(pos, 4, idx, 2, &(meso_lp_options){.region = nan_box}, "region axis 0");
    expect_error(pos, 4, idx, 2, &(meso_lp_options){.order = 3}, "order");

    meso_lp_field* f = NULL;
    meso_error err;
    assert(meso_lp_field_create(pos, 4, idx, 2, NULL, &f, &err) == MESO_OK);
    meso_lp_options o = meso_lp_field_options(f);
    assert(o.p == 3.0 && o.theta == MESO_LP_DEFAULT_THETA && o.order == 2 && o.near_radius == 0.0);
    assert(fabs(meso_lp_field_area(f) - 1.0) < 1e-12);
    double d = -1, g[3] = {1, 1, 1};
    double on[3] = {0.25, 0.25, 0.0}, nanx[3] = {0, NAN, 0}, ok[3] = {0.25, 0.25, 0.1};
    assert(meso_lp_eval(f, on, &d, g) == MESO_ERR_INVALID_ARG && d == 0.0 && g[0] == 0.0);
    assert(meso_lp_eval_exact(f, nanx, &d, g) == MESO_ERR_INVALID_ARG);
    assert(meso_lp_eval(NULL, ok, &d, g) == MESO_ERR_INVALID_ARG);
    assert(meso_lp_eval(f, ok, &d, NULL) == MESO_OK && d > 0.0);
    meso_lp_field_destroy(f);
    meso_lp_field_destroy(NULL);
}

/* >>determinism across threads and speed ------------------------------------ */

typedef struct worker {
    const meso_lp_field* f;
    const double* pts;
    double* out; /* 4 per point */
    int first, count;
} worker;

static void* worker_run(void* arg)
{
    worker* w = arg;
    for (int i = w->first; i < w->first + w->count; ++i)
        if (meso_lp_eval(w->f, w->pts + 3 * i, &w->out[4 * i], &w->out[4 * i + 1]) != MESO_OK)
            w->out[4 * i] = NAN;
    return NULL;
}

static void test_threads_and_speed(void)
{
    meso_mesh m = {0};
    /* wingnut.obj (bundled, CC BY 4.0, 6090 triangles with needles up to
     * aspect 100) stands in for the armadillo read before from outside the
     * repository, which may
     * not be bundled (Stanford's terms). Only determinism is asserted here. */
    if (!test_load_mesh(test_data("wingnut.obj"), &m))
        return;
    double lo[3], hi[3], size = meso_mesh_bounds(&m, lo, hi);
    meso_lp_field* f = NULL;
    meso_error err;
    double t0 = meso_seconds();
    assert(meso_lp_field_create(m.positions, m.vertex_count, m.indices, m.triangle_count, NULL, &f, &err) == MESO_OK);
    double t_build = meso_seconds() - t0;

    /* Points just off the surface (vertex + 1% of the size along the normal,
     * both sides), as the director ODE will ask. */
    enum { N = 2000 };
    static double pts[3 * N], a[4 * N], b[4 * N];
    uint64_t s = 0x5eedULL;
    for (int i = 0; i < N; ++i) {
        uint32_t v = (uint32_t)(test_rng_next(&s) % m.vertex_count);
        double off = (i & 1 ? 0.01 : -0.01) * size;
        for (int k = 0; k < 3; ++k)
            pts[3 * i + k] = m.positions[3 * v + k] + (m.normals ? off * m.normals[3 * v + k] : off);
    }
    worker one = {f, pts, a, 0, N};
    t0 = meso_seconds();
    worker_run(&one);
    double t_bh = meso_seconds() - t0;
    pthread_t th[2];
    worker two[2] = {{f, pts, b, 0, N / 2}, {f, pts, b, N / 2, N - N / 2}};
    for (int i = 0; i < 2; ++i)
        assert(pthread_create(&th[i], NULL, worker_run, &two[i]) == 0);
    for (int i = 0; i < 2; ++i)
        assert(pthread_join(th[i], NULL) == 0);
    assert(memcmp(a, b, sizeof(a)) == 0); /* bit-identical whatever the threading */

    const int nexact = 200;
    t0 = meso_seconds();
    for (int i = 0; i < nexact; ++i) {
        double d, g[3];
        assert(meso_lp_eval_exact(f, pts + 3 * i, &d, g) == MESO_OK);
    }
    double t_exact = meso_seconds() - t0;
    fprintf(stderr, "    %s (%u triangles, points 1%% of the size off the surface, 1 thread): build %.3f s;"
            " exact %.0f points/s; Barnes-Hut:\n", "wingnut", m.triangle_count, t_build,
            nexact / t_exact);
    static const double ths[3] = {0.5, 0.3, 0.2};
    for (int ti = 0; ti < 3; ++ti) {
        meso_lp_stats st = {0};
        t0 = meso_seconds();
        for (int i = 0; i < N; ++i) {
            double d, g[3];
            assert(meso_lp_eval_ex(f, pts + 3 * i, ths[ti], 0.0, &d, g, &st) == MESO_OK);
        }
        double t = meso_seconds() - t0;
        fprintf(stderr, "      theta %.1f: %.0f points/s (%.0f exact + %.0f far tris + %.0f multipoles per point)\n",
                ths[ti], N / t, (double)st.exact_triangles / N, (double)st.far_triangles / N,
                (double)st.multipoles / N);
    }
    (void)t_bh;
    meso_lp_field_destroy(f);

    /* p = 4 (quadrature near x) for comparison. */
    meso_lp_options o4 = {.p = 4.0};
    f = make_field(&m, &o4);
    t0 = meso_seconds();
    for (int i = 0; i < N / 4; ++i) {
        double d, g[3];
        assert(meso_lp_eval(f, pts + 3 * i, &d, g) == MESO_OK);
    }
    fprintf(stderr, "    p = 4 (quadrature near x): Barnes-Hut default theta %.0f points/s\n", (N / 4) / (meso_seconds() - t0));
    meso_lp_field_destroy(f);
    meso_mesh_free(&m);
}

int main(void)
{
    TEST_RUN(test_triangle_vs_brute_force);
    TEST_RUN(test_gradient_fd);
    TEST_RUN(test_barnes_hut);
    TEST_RUN(test_symmetric_fields);
    TEST_RUN(test_far_field);
    TEST_RUN(test_localised);
    TEST_RUN(test_region);
    TEST_RUN(test_bad_input);
    TEST_RUN(test_threads_and_speed);
    fprintf(stderr, "lp_distance: all tests passed\n");
    return 0;
}
