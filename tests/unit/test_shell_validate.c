/* Shell validation, pure part (bake/shell_validate.c): the Bernstein form of
 * det J against the analytic 3×3 determinant, the conservative inversion
 * test against dense sampling and an exact per-edge oracle, thickness ratios,
 * argument checks. Needs no adapter. */
#include "test_util.h"

#include <string.h>

#include "shell_validate.h"

/* Φ(u,v,w) = B(u,v) + w D(u,v), λ = (1−u−v, u, v). */
static void phi(const double b[9], const double d[9], double u, double v, double w, double out[3])
{
    const double l[3] = {1.0 - u - v, u, v};
    for (int k = 0; k < 3; ++k) {
        out[k] = 0.0;
        for (int i = 0; i < 3; ++i)
            out[k] += l[i] * (b[3 * i + k] + w * d[3 * i + k]);
    }
}

/* det [Φ_u Φ_v Φ_w], the partial derivatives written out directly and the
 * determinant by cofactor expansion; *scale = |Φ_u||Φ_v||Φ_w|. */
static double det_direct(const double b[9], const double d[9], double u, double v, double w, double* scale)
{
    double pu[3], pv[3], pw[3];
    for (int k = 0; k < 3; ++k) {
        pu[k] = (b[3 + k] - b[k]) + w * (d[3 + k] - d[k]);
        pv[k] = (b[6 + k] - b[k]) + w * (d[6 + k] - d[k]);
        pw[k] = (1.0 - u - v) * d[k] + u * d[3 + k] + v * d[6 + k];
    }
    if (scale)
        *scale = sqrt(pu[0] * pu[0] + pu[1] * pu[1] + pu[2] * pu[2]) * sqrt(pv[0] * pv[0] + pv[1] * pv[1] + pv[2] * pv[2]) *
                 sqrt(pw[0] * pw[0] + pw[1] * pw[1] + pw[2] * pw[2]);
    return pu[0] * (pv[1] * pw[2] - pv[2] * pw[1]) - pv[0] * (pu[1] * pw[2] - pu[2] * pw[1]) +
           pw[0] * (pu[1] * pv[2] - pu[2] * pv[1]);
}

static void random_point(uint64_t* rng, double* u, double* v, double* w)
{
    *u = test_rng_uniform(rng, 0, 1);
    *v = test_rng_uniform(rng, 0, 1);
    if (*u + *v > 1.0) {
        *u = 1.0 - *u;
        *v = 1.0 - *v;
    }
    *w = test_rng_uniform(rng, 0, 1);
}

/* A random prism: base in a unit box, directors = h·n + noise (noise 0 gives
 * parallel directors along the base normal). */
static void random_prism(uint64_t* rng, double noise, double b[9], double d[9])
{
    for (int k = 0; k < 9; ++k)
        b[k] = test_rng_uniform(rng, -1, 1);
    double e1[3], e2[3], n[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = b[3 + k] - b[k];
        e2[k] = b[6 + k] - b[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    double h = test_rng_uniform(rng, 0.05, 1.0);
    for (int i = 0; i < 3; ++i)
        for (int k = 0; k < 3; ++k)
            d[3 * i + k] = h * n[k] / ln + noise * test_rng_uniform(rng, -1, 1);
}

static void bernstein_equals_determinant(void)
{
    uint64_t rng = 0x1234567ULL;
    double worst = 0.0;
    for (int p = 0; p < 2000; ++p) {
        double b[9], d[9], c[9];
        random_prism(&rng, p % 2 ? 2.0 : 0.3, b, d);
        meso_shell_jacobian_bernstein(b, d, c);
        for (int s = 0; s < 50; ++s) {
            double u, v, w, scale;
            random_point(&rng, &u, &v, &w);
            double ref = det_direct(b, d, u, v, w, &scale);
            double got = meso_shell_jacobian_eval(c, u, v, w);
            double rel = fabs(got - ref) / (fabs(ref) > scale ? fabs(ref) : scale);
            worst = rel > worst ? rel : worst;
            assert(rel < 1e-9);
        }
        /* Corners: c[i][0] and c[i][2] (c[3i], c[3i+2]) are the exact values there. */
        const double uv[3][2] = {{0, 0}, {1, 0}, {0, 1}};
        for (int i = 0; i < 3; ++i) {
            double scale;
            double r0 = det_direct(b, d, uv[i][0], uv[i][1], 0.0, &scale);
            assert(fabs(c[3 * i + 0] - r0) <= 1e-12 * (scale + 1e-300));
            double r1 = det_direct(b, d, uv[i][0], uv[i][1], 1.0, &scale);
            assert(fabs(c[3 * i + 2] - r1) <= 1e-12 * (scale + 1e-300));
        }
    }
    /* And against a finite difference of Φ itself (independent of the
     * derivative formulas), to 1e-6 relative. */
    for (int p = 0; p < 200; ++p) {
        double b[9], d[9], c[9];
        random_prism(&rng, 1.0, b, d);
        meso_shell_jacobian_bernstein(b, d, c);
        double u, v, w, scale, col[3][3], x1[3], x0[3];
        random_point(&rng, &u, &v, &w);
        det_direct(b, d, u, v, w, &scale);
        const double hstep = 1e-5;
        for (int a = 0; a < 3; ++a) {
            double q[3] = {u, v, w};
            q[a] += hstep;
            phi(b, d, q[0], q[1], q[2], x1);
            q[a] -= 2 * hstep;
            phi(b, d, q[0], q[1], q[2], x0);
            for (int k = 0; k < 3; ++k)
                col[a][k] = (x1[k] - x0[k]) / (2 * hstep);
        }
        double fd = col[0][0] * (col[1][1] * col[2][2] - col[1][2] * col[2][1]) -
                    col[1][0] * (col[0][1] * col[2][2] - col[0][2] * col[2][1]) +
                    col[2][0] * (col[0][1] * col[1][2] - col[0][2] * col[1][1]);
        assert(fabs(fd - meso_shell_jacobian_eval(c, u, v, w)) <= 1e-6 * (scale + 1e-300));
    }
    fprintf(stderr, "    worst relative difference %.3g\n", worst);
}

static const double base_tri[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0}; /* CCW seen from +z */

static void straight_and_flipped(void)
{
    /* Parallel directors along the normal: a right prism, det J = const > 0. */
    const double up[9] = {0, 0, 0.3, 0, 0, 0.3, 0, 0, 0.3};
    assert(meso_shell_prism_check(base_tri, up, +1) == 0);
    assert(meso_shell_prism_check(base_tri, up, -1) == (MESO_PRISM_EDGE0 | MESO_PRISM_EDGE1 | MESO_PRISM_EDGE2));
    /* Interior shell: directors inward (−z), sign −1. */
    const double down[9] = {0, 0, -0.3, 0, 0, -0.3, 0, 0, -0.3};
    assert(meso_shell_prism_check(base_tri, down, -1) == 0);
    assert(meso_shell_prism_check(base_tri, down, +1) != 0);
    /* Sheared but valid. */
    const double shear[9] = {0.5, 0.2, 0.3, 0.5, 0.2, 0.3, 0.5, 0.2, 0.3};
    assert(meso_shell_prism_check(base_tri, shear, +1) == 0);
    /* Flipped top: top corners b_i + d_i = (0,0,h), (0,1,h), (1,0,h) — the
     * top triangle is mirrored, so det J < 0 at the top corners: proven. */
    const double flip[9] = {0, 0, 0.3, -1, 1, 0.3, 1, -1, 0.3};
    uint8_t s = meso_shell_prism_check(base_tri, flip, +1);
    assert(s != 0 && !(s & MESO_PRISM_UNDECIDED));
    double c[9];
    meso_shell_jacobian_bernstein(base_tri, flip, c);
    assert(c[5] < 0 && c[8] < 0);
    /* A zero director: the prism is collapsed along that edge (det J = 0). */
    const double zero[9] = {0, 0, 0, 0, 0, 0.3, 0, 0, 0.3};
    assert(meso_shell_prism_check(base_tri, zero, +1) == MESO_PRISM_EDGE0);
}

/* Min of det J over a dense grid of the prism (u,v on the triangle). */
static double sampled_min(const double b[9], const double d[9], int n)
{
    double lo = INFINITY;
    for (int a = 0; a < n; ++a)
        for (int bb = 0; a + bb < n; ++bb)
            for (int k = 0; k < n; ++k) {
                double val = det_direct(b, d, (double)a / (n - 1), (double)bb / (n - 1), (double)k / (n - 1), NULL);
                lo = val < lo ? val : lo;
            }
    return lo;
}

static void twisted_prism_inverted_inside(void)
{
    /* Base: a triangle centred at the origin in the xy plane. Top: the base
     * twisted by θ about z and lifted by h, directors perturbed. A half
     * turn (θ = π) pinches the mid-section to a point (det J = 0 there); near
     * it, perturbations give prisms that are positive at all 6 corners but
     * negative inside. Search for one, verify by direct evaluation. */
    const double b[9] = {-0.5, -0.3, 0, 0.5, -0.3, 0, 0.0, 0.6, 0};
    uint64_t rng = 99;
    int found = 0;
    for (int attempt = 0; attempt < 10000 && found < 20; ++attempt) {
        double th = test_rng_uniform(&rng, 2.6, 3.6), h = 0.4, d[9];
        for (int i = 0; i < 3; ++i) {
            const double x = b[3 * i], y = b[3 * i + 1];
            d[3 * i + 0] = cos(th) * x - sin(th) * y - x + test_rng_uniform(&rng, -0.1, 0.1);
            d[3 * i + 1] = sin(th) * x + cos(th) * y - y + test_rng_uniform(&rng, -0.1, 0.1);
            d[3 * i + 2] = h + test_rng_uniform(&rng, -0.1, 0.1);
        }
        const double uv[3][2] = {{0, 0}, {1, 0}, {0, 1}};
        int corners_ok = 1;
        for (int i = 0; i < 3; ++i)
            for (int w = 0; w < 2; ++w)
                corners_ok &= det_direct(b, d, uv[i][0], uv[i][1], w, NULL) > 0.0;
        if (!corners_ok || !(sampled_min(b, d, 30) < 0.0))
            continue;
        uint8_t s = meso_shell_prism_check(b, d, +1);
        assert(s != 0);
        if (found == 0)
            fprintf(stderr, "    found after %d attempts: theta %.3f, verdict 0x%02x, sampled min %.3g\n", attempt + 1,
                    th, s, sampled_min(b, d, 30));
        ++found;
    }
    assert(found >= 20);
}

/* Exact oracle per vertical edge: q(w) = a(1−w)² + 2m w(1−w) + e w² > 0 on
 * [0,1] iff a > 0, e > 0 and m > −sqrt(a e) (the minimum of the quadratic). */
static int exact_valid(const double b[9], const double d[9])
{
    double c[9];
    meso_shell_jacobian_bernstein(b, d, c);
    for (int i = 0; i < 3; ++i)
        if (!(c[3 * i + 0] > 0 && c[3 * i + 2] > 0 && c[3 * i + 1] > -sqrt(c[3 * i + 0] * c[3 * i + 2])))
            return 0;
    return 1;
}

static void brute_force_never_false_valid(void)
{
    uint64_t rng = 0xBEEF;
    enum { N = 3000, GRID = 30 };
    int valid = 0, inverted = 0, sampled_negative = 0, false_inverted_sampling = 0, false_inverted_exact = 0,
        undecided = 0, corners_ok_inside_bad = 0;
    for (int p = 0; p < N; ++p) {
        double b[9], d[9];
        random_prism(&rng, test_rng_uniform(&rng, 0.0, 1.5), b, d);
        uint8_t s = meso_shell_prism_check(b, d, +1);
        double lo = sampled_min(b, d, GRID);
        int neg = !(lo > 0.0);
        sampled_negative += neg;
        if (s == 0) {
            ++valid;
            assert(!neg); /* no false "valid" */
            assert(exact_valid(b, d));
        } else {
            ++inverted;
            undecided += (s & MESO_PRISM_UNDECIDED) != 0;
            false_inverted_sampling += !neg;
            false_inverted_exact += exact_valid(b, d);
        }
        double c[9];
        meso_shell_jacobian_bernstein(b, d, c);
        if (neg && c[0] > 0 && c[3] > 0 && c[6] > 0 && c[2] > 0 && c[5] > 0 && c[8] > 0)
            ++corners_ok_inside_bad;
    }
    fprintf(stderr,
            "    %d prisms: %d valid, %d inverted (%d undecided), sampling finds %d non-positive (%d of them "
            "positive at all 6 corners)\n"
            "    inverted but sampling positive: %d (%.2f %%); inverted but exactly valid: %d (%.3f %%)\n",
            N, valid, inverted, undecided, sampled_negative, corners_ok_inside_bad, false_inverted_sampling,
            100.0 * false_inverted_sampling / N, false_inverted_exact, 100.0 * false_inverted_exact / N);
    assert(valid > N / 10 && inverted > N / 10);
    assert(corners_ok_inside_bad > 0); /* the corner-only test would have missed these */
    assert(false_inverted_exact <= N / 1000);
}

/* A unit right tetrahedron, CCW outward. */
static const float tet_pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1};
static uint32_t tet_idx[12] = {0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3};

static void thickness_ratios(void)
{
    meso_mesh m = {4, 4, (float*)tet_pos, NULL, NULL, tet_idx, NULL};
    const float dir[12] = {0, 0, 0.1f, 0.2f, 0, 0, 0, 0.3f, 0, 0, 0, 0.4f};
    double lo, mean;
    uint32_t n;
    meso_error err = {0};
    assert(meso_shell_thickness_ratio(&m, dir, NULL, 0.2, &lo, &mean, &n, &err) == MESO_OK);
    assert(n == 4 && fabs(lo - 0.5) < 1e-6 && fabs(mean - 1.25) < 1e-6);
    const float req[4] = {0.1f, 0.4f, 0.0f /* not counted */, 0.4f};
    assert(meso_shell_thickness_ratio(&m, dir, req, 0.0, &lo, &mean, &n, &err) == MESO_OK);
    assert(n == 3 && fabs(lo - 0.5) < 1e-6 && fabs(mean - (1.0 + 0.5 + 1.0) / 3) < 1e-6);
    const float bad[4] = {0.1f, NAN, 0.1f, 0.1f};
    assert(meso_shell_thickness_ratio(&m, dir, bad, 0.0, &lo, &mean, &n, &err) == MESO_ERR_INVALID_ARG);
    /* An unused vertex (index 4) does not count. */
    const float pos5[15] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, 9, 9, 9};
    const float dir5[15] = {0, 0, 0.1f, 0.2f, 0, 0, 0, 0.3f, 0, 0, 0, 0.4f, 0, 0, 0};
    meso_mesh m5 = {5, 4, (float*)pos5, NULL, NULL, tet_idx, NULL};
    assert(meso_shell_thickness_ratio(&m5, dir5, NULL, 0.2, &lo, &mean, &n, &err) == MESO_OK);
    assert(n == 4 && fabs(lo - 0.5) < 1e-6);
}

/* The octahedron with vertices ±e_k, CCW outward. */
static const float oct_pos[18] = {1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1, 0, 0, 0, 1, 0, 0, -1};
static uint32_t oct_idx[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};

static void validate_entry_point(void)
{
    /* Radial directors of length 0.05: the offset is the octahedron scaled by
     * 1.05, clean. */
    meso_mesh m = {6, 8, (float*)oct_pos, NULL, NULL, oct_idx, NULL};
    float dir[18];
    for (int j = 0; j < 18; ++j)
        dir[j] = 0.05f * oct_pos[j];
    uint8_t per[8];
    meso_shell_report rep;
    meso_error err = {0};
    meso_result r = meso_shell_validate(&m, dir, NULL, 0.05, +1, per, &rep, &err);
#if MESO_HAVE_CGAL
    assert(r == MESO_OK);
    fprintf(stderr, "    octahedron: offset self %llu, offset/base %llu, base self %llu\n",
            (unsigned long long)rep.offset_self_intersections, (unsigned long long)rep.offset_base_intersections,
            (unsigned long long)rep.base_self_intersections);
    assert(rep.offset_self_intersections == 0 && rep.offset_base_intersections == 0 &&
           rep.base_self_intersections == 0);
#else
    assert(r == MESO_ERR_UNSUPPORTED && err.message[0]);
    assert(rep.offset_self_intersections == UINT64_MAX);
#endif
    assert(rep.prisms == 8 && rep.inverted_prisms == 0);
    assert(fabs(rep.thickness_ratio_min - 1.0) < 1e-6 && fabs(rep.thickness_ratio_mean - 1.0) < 1e-6);
    for (int t = 0; t < 8; ++t)
        assert(per[t] == 0);
    /* The same directors as an interior shell are all inverted. */
    r = meso_shell_validate(&m, dir, NULL, 0.05, -1, per, &rep, &err);
    assert(rep.inverted_prisms == 8);
    for (int t = 0; t < 8; ++t)
        assert(per[t] == (MESO_PRISM_EDGE0 | MESO_PRISM_EDGE1 | MESO_PRISM_EDGE2));
    /* Flattened onto the base (zero directors): every prism collapses, and
     * the coincident offset and base are not counted as intersecting. */
    const float zero[18] = {0};
    r = meso_shell_validate(&m, zero, NULL, 0.05, 1, per, &rep, &err);
    assert(rep.inverted_prisms == 8 && rep.thickness_ratio_min == 0.0);
#if MESO_HAVE_CGAL
    assert(r == MESO_OK && rep.offset_base_intersections == 0 && rep.offset_self_intersections == 0);
#endif

    /* Contract violations. */
    assert(meso_shell_validate(&m, dir, NULL, 0.05, 0, NULL, &rep, &err) == MESO_ERR_INVALID_ARG);
    assert(meso_shell_validate(&m, NULL, NULL, 0.05, 1, NULL, &rep, &err) == MESO_ERR_INVALID_ARG);
    uint32_t bad_idx[24];
    memcpy(bad_idx, oct_idx, sizeof(bad_idx));
    bad_idx[7] = 6;
    meso_mesh mb = {6, 8, (float*)oct_pos, NULL, NULL, bad_idx, NULL};
    assert(meso_shell_validate(&mb, dir, NULL, 0.05, 1, NULL, &rep, &err) == MESO_ERR_INVALID_ARG);
    (void)r;
}

int main(void)
{
    TEST_RUN(bernstein_equals_determinant);
    TEST_RUN(straight_and_flipped);
    TEST_RUN(twisted_prism_inverted_inside);
    TEST_RUN(brute_force_never_false_valid);
    TEST_RUN(thickness_ratios);
    TEST_RUN(validate_entry_point);
    return 0;
}
