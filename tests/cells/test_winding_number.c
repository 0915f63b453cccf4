/* Generalized winding numbers (bake/winding_number.c):
 *  - the hierarchical query against the exact sum over all triangles on four
 *    bundled meshes (max abs error printed and bounded);
 *  - closed meshes (sphere.obj: unit sphere; torus.obj: R = 1, r = 0.25
 *    around y) classified against the analytic solid: zero mismatches for
 *    points farther than 1e-3 from the mesh;
 *  - no leak: the open cube (tests/data/cube_no_bottom.obj), a sphere with
 *    every face twice, a sphere with 5% of its faces deleted;
 *  - 1 and 2 threads give the same bits; build errors and their codes;
 *  - timings (printed, not asserted). */
#include "meso_clock.h"
#include "test_util.h"

#include <string.h>
#include <time.h>

#include "adapters.h"
#include "winding_number.h"

/* Largest |fast - exact| accepted for a surface taken once (beta =
 * MESO_WINDING_BETA, order 2); measured maxima are printed (winding_number.h
 * lists them). */
#define FAST_TOL 0.05

/* >>mesh helpers ------------------------------------------------------------ */

/* A bundled mesh, read by the project's reader (bake/adapters). */
static meso_mesh load_obj(const char* name)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(name), &m, NULL, &err) == MESO_OK);
    assert(m.vertex_count > 0 && m.triangle_count > 0);
    return m;
}

static meso_mesh copy_mesh(const meso_mesh* src, uint32_t triangle_count)
{
    meso_mesh m = {0};
    m.vertex_count = src->vertex_count;
    m.triangle_count = triangle_count;
    m.positions = malloc(sizeof(float) * 3 * m.vertex_count);
    memcpy(m.positions, src->positions, sizeof(float) * 3 * m.vertex_count);
    m.indices = malloc(sizeof(uint32_t) * 3 * (size_t)triangle_count);
    return m;
}

static meso_winding* build(const meso_mesh* m)
{
    meso_winding* t = NULL;
    meso_error err;
    const meso_result r = meso_winding_build(m, 0, &t, &err);
    if (r != MESO_OK)
        fprintf(stderr, "build failed: %s\n", err.message);
    assert(r == MESO_OK && t);
    return t;
}

static void bounds(const meso_mesh* m, double lo[3], double hi[3])
{
    (void)meso_mesh_bounds(m, lo, hi);
}

/* n points uniform in the bounding box grown by `grow` of its size per side. */
static double* box_points(const meso_mesh* m, size_t n, double grow, uint64_t seed)
{
    double lo[3], hi[3];
    bounds(m, lo, hi);
    double* p = malloc(sizeof(double) * 3 * n);
    uint64_t s = seed;
    for (size_t i = 0; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const double e = hi[k] - lo[k];
            p[3 * i + k] = test_rng_uniform(&s, lo[k] - grow * e, hi[k] + grow * e);
        }
    return p;
}


/* >>analytic solids --------------------------------------------------------- */

typedef double (*sdf_fn)(const double p[3]);

static double sdf_sphere(const double p[3])
{
    return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1.0;
}

static double sdf_torus(const double p[3])
{
    const double rho = sqrt(p[0] * p[0] + p[2] * p[2]) - 1.0;
    return sqrt(rho * rho + p[1] * p[1]) - 0.25;
}

/* Range [lo, hi] of the analytic signed distance over the mesh (dense
 * barycentric samples of every face): the polyhedron sits in this band around
 * the analytic surface. The sdf is 1-Lipschitz, so a point with sdf < lo - e
 * or > hi + e is farther than e from the mesh. */
static void mesh_band(const meso_mesh* m, sdf_fn sdf, double* lo, double* hi)
{
    const int S = 12;
    *lo = HUGE_VAL;
    *hi = -HUGE_VAL;
    for (uint32_t f = 0; f < m->triangle_count; ++f) {
        const float* v[3];
        for (int k = 0; k < 3; ++k)
            v[k] = &m->positions[3 * (size_t)m->indices[3 * (size_t)f + k]];
        for (int i = 0; i <= S; ++i)
            for (int j = 0; i + j <= S; ++j) {
                const double a = (double)i / S, b = (double)j / S, c = 1.0 - a - b;
                double p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = a * v[0][k] + b * v[1][k] + c * v[2][k];
                const double d = sdf(p);
                *lo = d < *lo ? d : *lo;
                *hi = d > *hi ? d : *hi;
            }
    }
}

/* Classify n points against the analytic solid, skipping those within
 * `margin` of the band; returns mismatches, counts the tested points. */
static size_t classify(const meso_winding* t, sdf_fn sdf, double band_lo, double band_hi, double margin,
                       const double* p, size_t n, size_t* tested, double* min_in, double* max_out)
{
    double* w = malloc(sizeof(double) * n);
    meso_winding_query_many(t, p, n, w, 0);
    size_t bad = 0;
    for (size_t i = 0; i < n; ++i) {
        const double d = sdf(&p[3 * i]);
        int truth;
        if (d < band_lo - margin)
            truth = 1;
        else if (d > band_hi + margin)
            truth = 0;
        else
            continue;
        ++*tested;
        if (truth && w[i] < *min_in)
            *min_in = w[i];
        if (!truth && w[i] > *max_out)
            *max_out = w[i];
        bad += meso_winding_inside(w[i]) != truth;
    }
    free(w);
    return bad;
}

/* Box points plus points near the analytic surface: p0 pushed along the sdf
 * gradient (numerical) by s in [-spread, spread]. */
static double* near_points(sdf_fn sdf, const double lo[3], const double hi[3], size_t n, double spread, uint64_t seed)
{
    double* p = malloc(sizeof(double) * 3 * n);
    uint64_t s = seed;
    for (size_t i = 0; i < n; ++i) {
        double q[3];
        for (int k = 0; k < 3; ++k)
            q[k] = test_rng_uniform(&s, lo[k], hi[k]);
        /* Project onto the surface with a few Newton steps, then offset. */
        for (int it = 0; it < 8; ++it) {
            const double d = sdf(q), h = 1e-6;
            double g[3], gl = 0.0;
            for (int k = 0; k < 3; ++k) {
                double qh[3] = {q[0], q[1], q[2]};
                qh[k] += h;
                g[k] = (sdf(qh) - d) / h;
                gl += g[k] * g[k];
            }
            gl = sqrt(gl);
            if (gl < 1e-9)
                break;
            const double off = it == 7 ? test_rng_uniform(&s, -spread, spread) : 0.0;
            for (int k = 0; k < 3; ++k)
                q[k] -= (d - off) * g[k] / gl;
        }
        memcpy(&p[3 * i], q, sizeof(q));
    }
    return p;
}

/* >>tests ------------------------------------------------------------------- */

static void fast_matches_exact(void)
{
    const char* names[] = {"sphere.obj", "torus.obj", "spot_low_resolution.obj", "wingnut.obj"};
    const size_t n = 3000;
    const double tol = FAST_TOL;
    for (size_t k = 0; k < sizeof(names) / sizeof(names[0]); ++k) {
        meso_mesh m = load_obj(names[k]);
        meso_winding* t = build(&m);
        double* p = box_points(&m, n, 0.25, 0x5eed0000u + k);
        double* w1 = malloc(sizeof(double) * n);
        double* w2 = malloc(sizeof(double) * n);
        meso_winding_query_many(t, p, n, w1, 1);
        meso_winding_query_many(t, p, n, w2, 2);
        assert(memcmp(w1, w2, sizeof(double) * n) == 0); /* same bits for 1 and 2 threads */
        double max_err = 0.0, sum_err = 0.0;
        for (size_t i = 0; i < n; ++i) {
            assert(w1[i] == meso_winding_query(t, &p[3 * i]));
            const double e = fabs(w1[i] - meso_winding_exact(&m, &p[3 * i]));
            max_err = e > max_err ? e : max_err;
            sum_err += e;
        }
        uint32_t nodes, depth;
        meso_winding_stats(t, &nodes, &depth);
        fprintf(stderr, "    %-24s %5u tris %5u nodes depth %2u: |fast - exact| max %.2e mean %.2e (%zu points)\n",
                names[k], m.triangle_count, nodes, depth, max_err, sum_err / (double)n, n);
        assert(max_err < tol);
        free(p);
        free(w1);
        free(w2);
        meso_winding_free(t);
        meso_mesh_free(&m);
    }
}

static void check_closed(const char* label, const meso_mesh* m, sdf_fn sdf, double margin)
{
    double blo, bhi;
    mesh_band(m, sdf, &blo, &bhi);
    meso_winding* t = build(m);
    double lo[3], hi[3];
    bounds(m, lo, hi);
    for (int k = 0; k < 3; ++k) {
        const double e = hi[k] - lo[k];
        lo[k] -= 0.25 * e;
        hi[k] += 0.25 * e;
    }
    size_t tested = 0, bad = 0;
    double min_in = HUGE_VAL, max_out = -HUGE_VAL;
    double* p = box_points(m, 20000, 0.25, 0xb0c5u);
    bad += classify(t, sdf, blo, bhi, margin, p, 20000, &tested, &min_in, &max_out);
    free(p);
    const double spread = (bhi - blo) + margin + 0.02;
    p = near_points(sdf, lo, hi, 20000, spread, 0x4ea4u);
    bad += classify(t, sdf, blo, bhi, margin, p, 20000, &tested, &min_in, &max_out);
    free(p);
    fprintf(stderr,
            "    %-28s band [%+.2e, %+.2e] margin %.0e: %zu points tested, %zu mismatches; "
            "min w inside %.4f, max w outside %.4f\n",
            label, blo, bhi, margin, tested, bad, min_in, max_out);
    assert(bad == 0);
    assert(tested > 20000);
    meso_winding_free(t);
}

static void closed_meshes_exact(void)
{
    meso_mesh s = load_obj("sphere.obj");
    check_closed("sphere.obj", &s, sdf_sphere, 1e-3);
    meso_mesh_free(&s);
    meso_mesh tor = load_obj("torus.obj");
    check_closed("torus.obj", &tor, sdf_torus, 1e-3);
    meso_mesh_free(&tor);
}

/* The cube [-1, 1]^3 without one face: inside, w = 1 - Omega_hole / 4 pi >
 * 1/2; outside, |w| = Omega_hole / 4 pi < 1/2 (a planar hole subtends less
 * than a half space). So every point off the surface is classified right,
 * however close to the opening; the margin only keeps away from round-off. */
static void open_cube_does_not_leak(void)
{
    meso_mesh m = load_obj("cube_no_bottom.obj");
    meso_winding* t = build(&m);
    const double c[3] = {0, 0, 0};
    const double wc = meso_winding_query(t, c);
    assert(fabs(meso_winding_exact(&m, c) - 5.0 / 6.0) < 1e-9); /* 5 of 6 equal faces seen from the centre */
    assert(fabs(wc - 5.0 / 6.0) < FAST_TOL);
    const int G = 61;                   /* grid over [-1.5, 1.5]^3, step 0.05 */
    size_t in = 0, out = 0, bad = 0;
    double min_in = HUGE_VAL, max_out = -HUGE_VAL, max_abs_out = 0.0;
    for (int i = 0; i < G; ++i)
        for (int j = 0; j < G; ++j)
            for (int k = 0; k < G; ++k) {
                const double q[3] = {-1.5 + 0.05 * i + 0.0123, -1.5 + 0.05 * j + 0.0071, -1.5 + 0.05 * k + 0.0037};
                const double a = fmax(fabs(q[0]), fmax(fabs(q[1]), fabs(q[2])));
                if (fabs(a - 1.0) < 1e-3)
                    continue;
                const int truth = a < 1.0;
                const double w = meso_winding_query(t, q);
                assert(fabs(w - meso_winding_exact(&m, q)) < FAST_TOL);
                bad += meso_winding_inside(w) != truth;
                if (truth) {
                    ++in;
                    min_in = w < min_in ? w : min_in;
                } else {
                    ++out;
                    max_out = w > max_out ? w : max_out;
                    max_abs_out = fabs(w) > max_abs_out ? fabs(w) : max_abs_out;
                }
            }
    fprintf(stderr,
            "    open cube: w(centre) = %.6f; %zu inside (min w %.4f), %zu outside (max w %.4f, max |w| %.4f), "
            "%zu misclassified\n",
            wc, in, min_in, out, max_out, max_abs_out, bad);
    assert(bad == 0);
    meso_winding_free(t);
    meso_mesh_free(&m);
}

static void duplicated_faces(void)
{
    meso_mesh s = load_obj("sphere.obj");
    meso_mesh d = copy_mesh(&s, 2 * s.triangle_count);
    memcpy(d.indices, s.indices, sizeof(uint32_t) * 3 * s.triangle_count);
    memcpy(d.indices + 3 * (size_t)s.triangle_count, s.indices, sizeof(uint32_t) * 3 * s.triangle_count);
    meso_winding* t = build(&d);
    const double c[3] = {0.1, -0.2, 0.05};
    const double w = meso_winding_query(t, c);
    const double we = meso_winding_exact(&d, c);
    fprintf(stderr, "    every face twice: w inside = %.6f exact, %.6f fast (doubles)\n", we, w);
    assert(fabs(we - 2.0) < 1e-9 && fabs(w - we) < 2 * FAST_TOL); /* errors double too */
    meso_winding_free(t);
    check_closed("sphere.obj, every face twice", &d, sdf_sphere, 1e-3);
    meso_mesh_free(&d);
    meso_mesh_free(&s);
}

static void sphere_with_holes(void)
{
    meso_mesh s = load_obj("sphere.obj");
    meso_mesh h = copy_mesh(&s, s.triangle_count);
    uint64_t rng = 0x401e5u;
    uint32_t kept = 0;
    for (uint32_t f = 0; f < s.triangle_count; ++f)
        if (test_rng_uniform(&rng, 0.0, 1.0) >= 0.05)
            memcpy(&h.indices[3 * (size_t)kept++], &s.indices[3 * (size_t)f], 3 * sizeof(uint32_t));
    h.triangle_count = kept;
    fprintf(stderr, "    sphere with holes: %u of %u faces deleted\n", s.triangle_count - kept, s.triangle_count);
    assert(s.triangle_count - kept > s.triangle_count / 40);
    /* The band is that of the full sphere: deleting faces does not move the
     * remaining ones; the margin is the brief's 0.05. */
    double blo, bhi;
    mesh_band(&s, sdf_sphere, &blo, &bhi);
    meso_winding* t = build(&h);
    size_t tested = 0, bad = 0;
    double min_in = HUGE_VAL, max_out = -HUGE_VAL;
    const double lo[3] = {-1.5, -1.5, -1.5}, hi[3] = {1.5, 1.5, 1.5};
    double* p = box_points(&s, 20000, 0.25, 0x401eu);
    bad += classify(t, sdf_sphere, blo, bhi, 0.05, p, 20000, &tested, &min_in, &max_out);
    free(p);
    p = near_points(sdf_sphere, lo, hi, 20000, 0.15, 0x401fu);
    bad += classify(t, sdf_sphere, blo, bhi, 0.05, p, 20000, &tested, &min_in, &max_out);
    free(p);
    fprintf(stderr, "    sphere with holes, margin 0.05: %zu tested, %zu mismatches; min w inside %.4f, max w outside %.4f\n",
            tested, bad, min_in, max_out);
    assert(bad == 0);
    meso_winding_free(t);
    meso_mesh_free(&h);
    meso_mesh_free(&s);
}

static void build_errors(void)
{
    meso_winding* t = (meso_winding*)&t; /* must be reset to NULL */
    meso_error err;
    float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    uint32_t idx[3] = {0, 1, 2};
    meso_mesh m = {.vertex_count = 3, .triangle_count = 1, .positions = pos, .indices = idx};

    assert(meso_winding_build(NULL, 1, &t, &err) == MESO_ERR_INVALID_ARG && err.code == 0);
    meso_mesh e = m;
    e.triangle_count = 0;
    assert(meso_winding_build(&e, 1, &t, &err) == MESO_ERR_INVALID_ARG);
    assert(err.code == MESO_WINDING_ISSUE_EMPTY && t == NULL);
    idx[2] = 3;
    assert(meso_winding_build(&m, 1, &t, &err) == MESO_ERR_INVALID_ARG);
    assert(err.code == MESO_WINDING_ISSUE_INDEX && strstr(err.message, "vertex 3 of 3"));
    idx[2] = 2;
    pos[4] = NAN;
    assert(meso_winding_build(&m, 1, &t, &err) == MESO_ERR_INVALID_ARG);
    assert(err.code == MESO_WINDING_ISSUE_NONFINITE && strstr(err.message, "vertex 1"));
    pos[4] = 0;
    /* One triangle: a single leaf. From below (its back side) w > 0. */
    assert(meso_winding_build(&m, 1, &t, &err) == MESO_OK);
    const double q[3] = {0.2, 0.2, -0.1};
    const double w = meso_winding_query(t, q);
    assert(w > 0.0 && w < 0.5 && w == meso_winding_exact(&m, q));
    meso_winding_free(t);
    meso_winding_free(NULL);
}

static void timings(void)
{
    const char* names[] = {"spot_low_resolution.obj", "wingnut.obj"};
    const size_t n = 200000;
    for (size_t k = 0; k < 2; ++k) {
        meso_mesh m = load_obj(names[k]);
        double t0 = meso_seconds();
        meso_winding* t = build(&m);
        const double tb = meso_seconds() - t0;
        double* p = box_points(&m, n, 0.1, 0x7133u);
        double* w[2] = {malloc(sizeof(double) * n), malloc(sizeof(double) * n)};
        double qps[2];
        for (int th = 1; th <= 2; ++th) {
            t0 = meso_seconds();
            meso_winding_query_many(t, p, n, w[th - 1], th);
            qps[th - 1] = (double)n / (meso_seconds() - t0);
        }
        assert(memcmp(w[0], w[1], sizeof(double) * n) == 0);
        /* The brute force on a subset, for scale. */
        t0 = meso_seconds();
        double sum = 0.0;
        for (size_t i = 0; i < 2000; ++i)
            sum += meso_winding_exact(&m, &p[3 * i]);
        const double eqps = 2000.0 / (meso_seconds() - t0);
        fprintf(stderr,
                "    %-24s %5u tris: build %.2f ms; %.0f queries/s on 1 thread, %.0f on 2 (brute force %.0f/s, "
                "sum of w %.1f)\n",
                names[k], m.triangle_count, 1e3 * tb, qps[0], qps[1], eqps, sum);
        free(w[0]);
        free(w[1]);
        free(p);
        meso_winding_free(t);
        meso_mesh_free(&m);
    }
}

int main(void)
{
    TEST_RUN(build_errors);
    TEST_RUN(fast_matches_exact);
    TEST_RUN(closed_meshes_exact);
    TEST_RUN(open_cube_does_not_leak);
    TEST_RUN(duplicated_faces);
    TEST_RUN(sphere_with_holes);
    TEST_RUN(timings);
    return 0;
}
