/*
 * test_shell_repair.c — repair's round budget (bake/shell_hybrid.h,
 * MESO_SHELL_REPAIR_ROUNDS) on a slot much narrower than the shell.
 *
 * A closed U-shaped block (unit square cross-section with a slot of width
 * g cut down from the top to y = 0.2, extruded along z) gets plain normal
 * directors of length h = 0.05 of its diagonal. The offsets of the slot's
 * two walls cross unless the wall directors' x parts sum to less than g,
 * and repair shortens them by 0.8 a round, so it needs at least
 * r* = ceil(ln(g / (|dx_left| + |dx_right|)) / ln 0.8) rounds (analytic,
 * over the top-edge vertex pairs). For g = 2e-5 that is 40: more than the
 * 30 repair used to be allowed, when such bakes were refused (E3115).
 * Asserted: repair with the bake's budget leaves no bad
 * face, takes at least r* rounds, and the whole-shell validation (its own
 * code, not the incremental checks repair uses) finds nothing inverted and
 * no intersection; every wall director ends below g.
 */
#include "test_util.h"

#include <string.h>

#include "meso_bake.h"
#include "shell_directors.h"
#include "shell_hybrid.h"
#include "shell_validate.h"

enum { NP = 8, NZ = 4 };

static void slot_mesh(double g, meso_mesh* m)
{
    const double P[NP][2] = {{0, 0}, {1, 0}, {1, 1}, {0.5 + g / 2, 1}, {0.5 + g / 2, 0.2}, {0.5 - g / 2, 0.2},
                             {0.5 - g / 2, 1}, {0, 1}};
    /* the cross-section (counter-clockwise) in convex pieces */
    static const int caps[6][3] = {{0, 1, 4}, {1, 2, 3}, {1, 3, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 7}};
    memset(m, 0, sizeof(*m));
    m->vertex_count = NP * (NZ + 1);
    m->triangle_count = 2 * NP * NZ + 12;
    m->positions = malloc(sizeof(float) * 3 * m->vertex_count);
    m->indices = malloc(sizeof(uint32_t) * 3 * m->triangle_count);
    assert(m->positions && m->indices);
    for (int k = 0; k <= NZ; ++k)
        for (int i = 0; i < NP; ++i) {
            float* p = m->positions + 3 * (size_t)(k * NP + i);
            p[0] = (float)P[i][0], p[1] = (float)P[i][1], p[2] = (float)k / NZ;
        }
    uint32_t* f = m->indices;
    for (int k = 0; k < NZ; ++k)
        for (int i = 0; i < NP; ++i) {
            const uint32_t a = (uint32_t)(k * NP + i), b = (uint32_t)(k * NP + (i + 1) % NP), c = b + NP, d = a + NP;
            const uint32_t q[6] = {a, b, c, a, c, d};
            memcpy(f, q, sizeof(q));
            f += 6;
        }
    for (int t = 0; t < 6; ++t) {
        for (int j = 0; j < 3; ++j)
            *f++ = (uint32_t)(NZ * NP + caps[t][j]); /* top, seen from +z */
        for (int j = 2; j >= 0; --j)
            *f++ = (uint32_t)caps[t][j]; /* bottom, seen from -z */
    }
    assert(f == m->indices + 3 * (size_t)m->triangle_count);
}

int main(void)
{
    const double g = 2e-5;
    meso_mesh m;
    slot_mesh(g, &m);
    const double h = 0.05 * sqrt(3.0); /* 0.05 of the unit cube's diagonal, as --thickness-rel 0.05 */
    float* normals = malloc(sizeof(float) * 3 * m.vertex_count);
    float* d = malloc(sizeof(float) * 3 * m.vertex_count);
    assert(normals && d && meso_vertex_normals(&m, normals, NULL) == MESO_OK);
    for (size_t i = 0; i < 3 * (size_t)m.vertex_count; ++i)
        d[i] = (float)(h * normals[i]);
    /* The analytic lower bound: the offsets of the two walls' top-edge
     * vertices at the same z (normals half +-x, half +y) cross while
     * 0.8^r (|dx_left| + |dx_right|) >= g, and both shrink every round. */
    int need = 0;
    for (int k = 0; k <= NZ; ++k) {
        const float* dl = d + 3 * (size_t)(k * NP + 6); /* (0.5 - g/2, 1, z) */
        const float* dr = d + 3 * (size_t)(k * NP + 3); /* (0.5 + g/2, 1, z) */
        const int r = (int)ceil(log(g / (fabs(dl[0]) + fabs(dr[0]))) / log(0.8));
        need = r > need ? r : need;
    }
    uint32_t shortened = 0, rounds = 0, left = 0;
    meso_error err;
    assert(meso_shell_repair(&m, d, 1, MESO_SHELL_REPAIR_ROUNDS, 2, &shortened, &rounds, &left, &err) == MESO_OK);
    printf("slot %.0e under a %.4f shell: %u directors shortened in %u rounds (analytic lower bound %d, budget %d), "
           "%u faces left\n",
           g, h, shortened, rounds, need, MESO_SHELL_REPAIR_ROUNDS, left);
    assert(left == 0 && (int)rounds >= need && need > 30);
    meso_shell_report v;
    assert(meso_shell_validate(&m, d, NULL, h, 1, NULL, &v, &err) == MESO_OK);
    printf("validation: %u inverted, %u undecided, %llu offset self-, %llu offset/base intersections\n",
           v.inverted_prisms, v.undecided_prisms,
           (unsigned long long)v.offset_self_intersections, (unsigned long long)v.offset_base_intersections);
    assert(v.inverted_prisms == 0 && v.undecided_prisms == 0 && v.offset_self_intersections == 0 &&
           v.offset_base_intersections == 0);
    for (uint32_t i = 0; i < m.vertex_count; ++i) { /* the slot's walls: x = 0.5 -+ g / 2, y > 0.2 */
        const float* p = m.positions + 3 * (size_t)i;
        if (fabs(p[0] - 0.5) < g && p[1] > 0.3f)
            assert(fabs(d[3 * (size_t)i]) < g);
    }
    free(normals), free(d);
    meso_mesh_free(&m);
    puts("test_shell_repair: ok");
    return 0;
}
