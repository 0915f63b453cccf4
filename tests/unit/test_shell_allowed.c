/* test_shell_allowed.c — the thickness the geometry allows
 * (bake/shell_allowed.c, definition in shell_allowed.h) against brute force:
 * every ray against every triangle, in double, with another ray/triangle
 * test (plane, then barycentric signs), on the small bundled meshes, both
 * sides, thicknesses from 1 % to 100 % of the diagonal; the same bits for
 * 1 and 2 threads; closed forms on two facing plates and inside a sphere;
 * the summary of achieved/allowed. */
#include "test_util.h"

#include <string.h>

#include "adapters.h"
#include "test_mesh.h"
#include "shell_allowed.h"
#include "shell_directors.h"

#define CHECK_MSG(cond, ...)                                                  \
    do {                                                                      \
        if (!(cond)) {                                                        \
            fprintf(stderr, "    FAIL: " __VA_ARGS__);                       \
            fprintf(stderr, "\n");                                           \
            assert(cond);                                                     \
        }                                                                     \
    } while (0)

/* The ray o + t·u against triangle (a, b, c): t > 0, or INFINITY. Plane
 * first, then the point's barycentric signs (a hair of slack, so that a ray
 * through an edge is not lost to rounding either). */
static double brute_ray_triangle(const double o[3], const double u[3], const double a[3], const double b[3],
                                 const double c[3])
{
    double e1[3], e2[3], n[3], ao[3];
    for (int k = 0; k < 3; ++k) {
        e1[k] = b[k] - a[k];
        e2[k] = c[k] - a[k];
        ao[k] = a[k] - o[k];
    }
    n[0] = e1[1] * e2[2] - e1[2] * e2[1];
    n[1] = e1[2] * e2[0] - e1[0] * e2[2];
    n[2] = e1[0] * e2[1] - e1[1] * e2[0];
    const double den = n[0] * u[0] + n[1] * u[1] + n[2] * u[2];
    if (den == 0.0)
        return INFINITY;
    const double t = (n[0] * ao[0] + n[1] * ao[1] + n[2] * ao[2]) / den;
    if (!(t > 0.0))
        return INFINITY;
    const double p[3] = {o[0] + t * u[0], o[1] + t * u[1], o[2] + t * u[2]};
    const double* q[3] = {a, b, c};
    const double nn = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    for (int i = 0; i < 3; ++i) {
        const double* x = q[i];
        const double* y = q[(i + 1) % 3];
        double ex[3], px[3], cr[3];
        for (int k = 0; k < 3; ++k) {
            ex[k] = y[k] - x[k];
            px[k] = p[k] - x[k];
        }
        cr[0] = ex[1] * px[2] - ex[2] * px[1];
        cr[1] = ex[2] * px[0] - ex[0] * px[2];
        cr[2] = ex[0] * px[1] - ex[1] * px[0];
        if ((cr[0] * n[0] + cr[1] * n[1] + cr[2] * n[2]) / nn < -1e-12)
            return INFINITY;
    }
    return t;
}

/* allowed_v by the definition, over all triangles. */
static void brute_allowed(const meso_mesh* m, const float* normals, int sign, double h, double* out)
{
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        double o[3], u[3];
        for (int k = 0; k < 3; ++k) {
            o[k] = m->positions[3 * v + k];
            u[k] = sign * (double)normals[3 * v + k];
        }
        double best = INFINITY;
        for (uint32_t f = 0; f < m->triangle_count; ++f) {
            const uint32_t* t = m->indices + 3 * (size_t)f;
            if (t[0] == v || t[1] == v || t[2] == v)
                continue;
            double p[3][3];
            for (int c = 0; c < 3; ++c)
                for (int k = 0; k < 3; ++k)
                    p[c][k] = m->positions[3 * (size_t)t[c] + k];
            const double hit = brute_ray_triangle(o, u, p[0], p[1], p[2]);
            best = hit <= 2.0 * h && hit < best ? hit : best;
        }
        out[v] = fmin(h, 0.5 * best);
    }
}

static void against_brute_force(void)
{
    static const char* const names[] = {"spot_low_resolution.obj", "blub_fish_low_resolution.obj", "torus.obj",
                                        "sphere.obj", "wingnut.obj"};
    static const double rels[] = {0.01, 0.05, 0.1, 0.3, 1.0};
    for (size_t mi = 0; mi < sizeof(names) / sizeof(names[0]); ++mi) {
        meso_mesh m = {0};
        if (!test_load_mesh(test_data(names[mi]), &m))
            return;
        meso_error err;
        memset(&err, 0, sizeof(err));
        const uint32_t nv = m.vertex_count;
        float* normals = malloc(sizeof(float) * 3 * nv);
        double *fast = malloc(sizeof(double) * nv), *fast1 = malloc(sizeof(double) * nv),
               *slow = malloc(sizeof(double) * nv);
        assert(normals && fast && fast1 && slow);
        assert(meso_vertex_normals(&m, normals, &err) == MESO_OK);
        double lo[3], hi[3];
        const double diag = meso_mesh_bounds(&m, lo, hi);
        uint32_t limited = 0, checked = 0;
        for (size_t ri = 0; ri < sizeof(rels) / sizeof(rels[0]); ++ri)
            for (int sign = -1; sign <= 1; sign += 2) {
                const double h = rels[ri] * diag;
                assert(meso_shell_allowed(&m, normals, sign, h, 2, fast, &err) == MESO_OK);
                assert(meso_shell_allowed(&m, normals, sign, h, 1, fast1, &err) == MESO_OK);
                assert(memcmp(fast, fast1, sizeof(double) * nv) == 0); /* thread count: same bits */
                brute_allowed(&m, normals, sign, h, slow);
                for (uint32_t v = 0; v < nv; ++v) {
                    CHECK_MSG(fabs(fast[v] - slow[v]) <= 1e-9 * diag, "%s sign %d h %.3g vertex %u: %.17g vs %.17g",
                              names[mi], sign, h, v, fast[v], slow[v]);
                    limited += slow[v] < h;
                    ++checked;
                }
            }
        printf("    %s: %u (vertex, side, h) checked, %u limited by the geometry\n", names[mi], checked, limited);
        assert(limited > 0); /* the test exercises hits, not only empty rays */
        free(normals), free(fast), free(fast1), free(slow);
        meso_mesh_free(&m);
    }
}

/* Two plates facing each other 0.3 apart: the lower [0,1]^2 at z = 0
 * facing up, the upper [-1,2]^2 at z = 0.3 facing down. Lower vertices
 * meet the upper plate inside it: allowed = min(h, 0.15); upper vertices
 * look past the lower plate: allowed = h. Exterior (+1) along the normals. */
static void facing_plates(void)
{
    static const float pos[] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0, -1, -1, 0.3f, 2, -1, 0.3f, 2, 2, 0.3f, -1, 2, 0.3f};
    static const uint32_t idx[] = {0, 1, 2, 0, 2, 3, 4, 6, 5, 4, 7, 6};
    const meso_mesh m = {8, 4, (float*)pos, NULL, NULL, (uint32_t*)idx, NULL};
    float normals[24];
    double al[8];
    meso_error err;
    memset(&err, 0, sizeof(err));
    assert(meso_vertex_normals(&m, normals, &err) == MESO_OK);
    assert(normals[2] == 1.0f && normals[14] == -1.0f);
    for (int hi = 0; hi < 2; ++hi) {
        const double h = hi ? 1.0 : 0.1;
        assert(meso_shell_allowed(&m, normals, 1, h, 0, al, &err) == MESO_OK);
        for (int v = 0; v < 8; ++v) {
            const double want = v < 4 ? fmin(h, 0.5 * (double)0.3f) : h;
            CHECK_MSG(fabs(al[v] - want) < 1e-12, "plates h %g vertex %d: %.17g, want %.17g", h, v, al[v], want);
        }
        /* The other side looks away from both plates. */
        assert(meso_shell_allowed(&m, normals, -1, h, 0, al, &err) == MESO_OK);
        for (int v = 0; v < 8; ++v)
            assert(al[v] == h);
    }
    /* The summary: directors of 0.15 (all kept), 0.05 (a third: below
     * half), and 0 on the lower plate; the upper plate keeps 0.5 of h. */
    assert(meso_shell_allowed(&m, normals, 1, 1.0, 0, al, &err) == MESO_OK);
    float d[24] = {0};
    const float len[8] = {0.15f, 0.05f, 0.0f, 0.15f, 0.5f, 0.5f, 0.5f, 0.5f};
    for (int v = 0; v < 8; ++v)
        d[3 * v + 2] = len[v] * normals[3 * v + 2];
    meso_shell_allowed_summary s;
    memset(&s, 0, sizeof(s));
    double ratios[8];
    meso_shell_allowed_add(&m, d, al, 1.0, &s, ratios);
    assert(s.counted == 8 && s.limited == 4 && s.below_half == 2 && s.ratio_min == 0.0);
    assert(fabs(ratios[1] - 1.0 / 3.0) < 1e-6 && ratios[0] == 1.0 && ratios[4] == 0.5);
    assert(fabs(s.ratio_sum - (1.0 + 1.0 / 3.0 + 0.0 + 1.0 + 4 * 0.5)) < 1e-6);
    /* Contract. */
    assert(meso_shell_allowed(&m, normals, 0, 1.0, 0, al, &err) == MESO_ERR_INVALID_ARG);
    assert(meso_shell_allowed(&m, normals, 1, 0.0, 0, al, &err) == MESO_ERR_INVALID_ARG);
}

/* Inside a sphere the ray along the normal crosses the diameter: allowed =
 * min(h, R), the inscribed-ball bound, up to the tessellation. */
static void inside_sphere(void)
{
    meso_mesh m = {0};
    if (!test_load_mesh(test_data("sphere.obj"), &m))
        return;
    meso_error err;
    memset(&err, 0, sizeof(err));
    const uint32_t nv = m.vertex_count;
    float* normals = malloc(sizeof(float) * 3 * nv);
    double* al = malloc(sizeof(double) * nv);
    assert(normals && al && meso_vertex_normals(&m, normals, &err) == MESO_OK);
    double lo[3], hi[3], c[3], rmean = 0;
    meso_mesh_bounds(&m, lo, hi);
    for (int k = 0; k < 3; ++k)
        c[k] = 0.5 * (lo[k] + hi[k]);
    for (uint32_t v = 0; v < nv; ++v) {
        double r2 = 0;
        for (int k = 0; k < 3; ++k)
            r2 += (m.positions[3 * v + k] - c[k]) * (m.positions[3 * v + k] - c[k]);
        rmean += sqrt(r2) / nv;
    }
    assert(meso_shell_allowed(&m, normals, -1, 10.0 * rmean, 2, al, &err) == MESO_OK);
    double worst = 0;
    for (uint32_t v = 0; v < nv; ++v)
        worst = fmax(worst, fabs(al[v] - rmean) / rmean);
    printf("    sphere, inside: allowed within %.2f %% of the radius\n", 100 * worst);
    assert(worst < 0.02);
    free(normals), free(al);
    meso_mesh_free(&m);
}

int main(void)
{
    TEST_RUN(facing_plates);
    TEST_RUN(inside_sphere);
    TEST_RUN(against_brute_force);
    return 0;
}
