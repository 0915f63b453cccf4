/*
 * test_shell_envelope.c — an envelope repaired as it is drawn, from bottom
 * to top (bake/shell_envelope.h).
 *
 * spot_uv with envelope directors that lean apart: the top layer along the
 * normal tilted one way, the bottom layer against it tilted another way,
 * the tilts varying over the surface; each layer first repaired against
 * the base as a bake does (shell_hybrid.h). Asserted, with the whole-shell
 * validation (shell_validate.h, its own code, not the per-prism test the
 * stage uses):
 *  - before the stage, prisms from bottom to top invert (the case is one);
 *  - after it, none does and the top and bottom surfaces neither cross
 *    themselves nor each other; each layer still passes against the base;
 *  - no director got longer, at least those the stage counts changed,
 *    and not all did;
 *  - 1 and 2 threads give the same directors.
 */
#include "test_util.h"

#include <string.h>

#include "meso_bake.h"
#include "shell_directors.h"
#include "shell_envelope.h"
#include "shell_hybrid.h"
#include "shell_validate.h"

static double len3(const float* v)
{
    return sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
}

/* The shell from bottom to top as meso_shell_validate sees it. */
static meso_shell_report drawn(const meso_mesh* m, const float* d, double h)
{
    const size_t n = 3 * (size_t)m->vertex_count;
    float* pos = malloc(sizeof(float) * n);
    float* span = malloc(sizeof(float) * n);
    assert(pos && span);
    for (size_t i = 0; i < n; ++i) {
        pos[i] = m->positions[i] + d[n + i];
        span[i] = d[i] - d[n + i];
    }
    meso_mesh bottom = *m;
    bottom.positions = pos;
    meso_shell_report v;
    assert(meso_shell_validate(&bottom, span, NULL, h, 1, NULL, &v, NULL) == MESO_OK);
    free(pos), free(span);
    return v;
}

static void directors(const meso_mesh* m, double h, float* d)
{
    const size_t n = 3 * (size_t)m->vertex_count;
    float* nrm = malloc(sizeof(float) * n);
    assert(nrm && meso_vertex_normals(m, nrm, NULL) == MESO_OK);
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        const float* p = m->positions + 3 * (size_t)v;
        const float* nv = nrm + 3 * (size_t)v;
        for (int layer = 0; layer < 2; ++layer) {
            double t[3], l = 0;
            for (int k = 0; k < 3; ++k) {
                const double tilt = 0.9 * sin(9.0 * p[(k + 1 + layer) % 3] + 2.0 * k + 3.0 * layer);
                t[k] = nv[k] + tilt;
                l += t[k] * t[k];
            }
            l = sqrt(l);
            for (int k = 0; k < 3; ++k)
                d[(size_t)layer * n + 3 * (size_t)v + (size_t)k] = (float)((layer ? -h : h) * t[k] / l);
        }
    }
    free(nrm);
}

static void run(const meso_mesh* m, double h, int threads, float* d, uint32_t* out_shortened)
{
    const size_t n = 3 * (size_t)m->vertex_count;
    directors(m, h, d);
    for (int layer = 0; layer < 2; ++layer) {
        uint32_t s = 0, r = 0, l = 0;
        assert(meso_shell_repair(m, d + (size_t)layer * n, layer ? -1 : 1, MESO_SHELL_REPAIR_ROUNDS, threads, &s, &r,
                                 &l, NULL) == MESO_OK);
        assert(l == 0);
    }
    float* before = malloc(sizeof(float) * 2 * n);
    assert(before);
    memcpy(before, d, sizeof(float) * 2 * n);
    const meso_shell_report pre = drawn(m, d, h);
    uint32_t shortened = 0, rounds = 0, left = 0;
    assert(meso_shell_envelope_repair(m, d, MESO_SHELL_REPAIR_ROUNDS, threads, &shortened, &rounds, &left, NULL) ==
           MESO_OK);
    const meso_shell_report post = drawn(m, d, h);
    printf("threads %d: %u prisms inverted from bottom to top before, %u after; %u vertices shortened in %u rounds, "
           "%u left; %llu self- and %llu top/bottom intersections\n",
           threads, pre.inverted_prisms, post.inverted_prisms, shortened, rounds, left,
           (unsigned long long)post.offset_self_intersections, (unsigned long long)post.offset_base_intersections);
    assert(pre.inverted_prisms > 0);
    assert(left == 0 && post.inverted_prisms == 0 && post.offset_self_intersections == 0 &&
           post.offset_base_intersections == 0);
    for (int layer = 0; layer < 2; ++layer) {
        meso_shell_report v;
        assert(meso_shell_validate(m, d + (size_t)layer * n, NULL, h, layer ? -1 : 1, NULL, &v, NULL) == MESO_OK);
        assert(v.inverted_prisms == 0 && v.offset_self_intersections == 0 && v.offset_base_intersections == 0);
    }
    uint32_t changed = 0;
    for (uint32_t v = 0; v < 2 * m->vertex_count; ++v) {
        const float* a = before + 3 * (size_t)v;
        const float* b = d + 3 * (size_t)v;
        assert(len3(b) <= len3(a) * (1.0 + 1e-6));
        changed += memcmp(a, b, 3 * sizeof(float)) != 0;
    }
    assert(changed >= shortened && changed < 2 * m->vertex_count);
    *out_shortened = shortened;
    free(before);
}

int main(void)
{
    meso_mesh m;
    meso_error err;
    assert(meso_bake_load_mesh(test_data("spot_uv.obj"), NULL, &m, NULL, &err) == MESO_OK);
    double lo[3], hi[3], diag = 0;
    meso_mesh_bounds(&m, lo, hi);
    for (int k = 0; k < 3; ++k)
        diag += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    const double h = 0.05 * sqrt(diag);
    const size_t n = 3 * (size_t)m.vertex_count;
    float* d1 = malloc(sizeof(float) * 2 * n);
    float* d2 = malloc(sizeof(float) * 2 * n);
    assert(d1 && d2);
    uint32_t s1 = 0, s2 = 0;
    run(&m, h, 1, d1, &s1);
    run(&m, h, 2, d2, &s2);
    assert(s1 == s2 && !memcmp(d1, d2, sizeof(float) * 2 * n));
    free(d1), free(d2);
    meso_mesh_free(&m);
    puts("test_shell_envelope: ok");
    return 0;
}
