/*
 * test_mesh_orient.c — inside-out closed components are flipped, nothing
 * else is (bake/mesh_orient.c). Meshes are axis-aligned cubes built here,
 * so the expected signed volume of every component is known exactly
 * (edge^3, its sign from the winding), and "flipped" is checked face by
 * face against the cube as built.
 */
#undef NDEBUG /* this file uses assert() to verify algorithm correctness */
#include <assert.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_orient.h"

/* 12 triangles of the unit cube, counter-clockwise seen from outside. */
static const uint32_t cube_faces[12][3] = {
    {0, 2, 1}, {0, 3, 2}, /* z = 0 (normal -z) */
    {4, 5, 6}, {4, 6, 7}, /* z = 1 */
    {0, 1, 5}, {0, 5, 4}, /* y = 0 */
    {2, 3, 7}, {2, 7, 6}, /* y = 1 */
    {1, 2, 6}, {1, 6, 5}, /* x = 1 */
    {3, 0, 4}, {3, 4, 7}, /* x = 0 */
};
static const float cube_corners[8][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

typedef struct cube {
    float origin[3], edge;
    int inward;    /* faces point inward */
    int open;      /* drop the last face (a hole) */
} cube;

/* A mesh of `n` cubes with normals (the corner direction from the cube's
 * centre, outward for outward cubes) and corner uvs (distinct per corner). */
static meso_mesh make_mesh(const cube* cubes, int n)
{
    meso_mesh m = {0};
    m.vertex_count = 8u * (uint32_t)n;
    m.positions = malloc(sizeof(float) * 3 * m.vertex_count);
    m.normals = malloc(sizeof(float) * 3 * m.vertex_count);
    m.indices = malloc(sizeof(uint32_t) * 3 * 12 * (size_t)n);
    m.corner_uvs = malloc(sizeof(float) * 6 * 12 * (size_t)n);
    assert(m.positions && m.normals && m.indices && m.corner_uvs);
    for (int c = 0; c < n; ++c) {
        for (int v = 0; v < 8; ++v)
            for (int k = 0; k < 3; ++k) {
                m.positions[3 * (8 * c + v) + k] = cubes[c].origin[k] + cubes[c].edge * cube_corners[v][k];
                m.normals[3 * (8 * c + v) + k] = (cube_corners[v][k] - 0.5f) * (cubes[c].inward ? -1.0f : 1.0f);
            }
        for (int f = 0; f < 12 - cubes[c].open; ++f) {
            uint32_t* ix = m.indices + 3 * m.triangle_count;
            ix[0] = 8u * (uint32_t)c + cube_faces[f][0];
            ix[1] = 8u * (uint32_t)c + cube_faces[f][cubes[c].inward ? 2 : 1];
            ix[2] = 8u * (uint32_t)c + cube_faces[f][cubes[c].inward ? 1 : 2];
            for (int k = 0; k < 6; ++k)
                m.corner_uvs[6 * m.triangle_count + k] = (float)(100 * m.triangle_count + k);
            m.triangle_count++;
        }
    }
    return m;
}

/* Whether face f of the mesh is wound as the outward cube face. */
static int face_outward(const meso_mesh* m, uint32_t f, const cube* cubes, int n)
{
    uint32_t base = 0;
    for (int c = 0; c < n; ++c) {
        const uint32_t count = 12u - (uint32_t)cubes[c].open;
        if (f < base + count) {
            const uint32_t* want = cube_faces[f - base];
            const uint32_t* ix = m->indices + 3 * f;
            const uint32_t off = 8u * (uint32_t)c;
            if (ix[0] == off + want[0] && ix[1] == off + want[1] && ix[2] == off + want[2])
                return 1;
            assert(ix[0] == off + want[0] && ix[1] == off + want[2] && ix[2] == off + want[1]);
            return 0;
        }
        base += count;
    }
    assert(0);
    return 0;
}

/* Orients n cubes and checks: `flipped[c]` says which cubes must have been
 * turned; every face of cube c is then outward iff inward == flipped. */
static void run(const char* name, const cube* cubes, int n, const int* flipped, uint32_t want_closed)
{
    meso_mesh m = make_mesh(cubes, n);
    meso_mesh before = m;
    before.normals = malloc(sizeof(float) * 3 * m.vertex_count);
    before.corner_uvs = malloc(sizeof(float) * 6 * m.triangle_count);
    memcpy(before.normals, m.normals, sizeof(float) * 3 * m.vertex_count);
    memcpy(before.corner_uvs, m.corner_uvs, sizeof(float) * 6 * m.triangle_count);
    meso_mesh_orientation o;
    meso_error err = {0};
    assert(meso_mesh_orient_outward(&m, &o, &err) == MESO_OK);
    uint32_t want_flips = 0, want_faces = 0, base = 0;
    for (int c = 0; c < n; ++c) {
        want_flips += (uint32_t)flipped[c];
        want_faces += flipped[c] ? 12u - (uint32_t)cubes[c].open : 0;
        const uint32_t count = 12u - (uint32_t)cubes[c].open;
        for (uint32_t f = base; f < base + count; ++f) {
            assert(face_outward(&m, f, cubes, n) == (cubes[c].inward == flipped[c]));
            /* corner uvs follow their corners: corner 1 and 2 swapped */
            const float* a = m.corner_uvs + 6 * f;
            const float* b = before.corner_uvs + 6 * f;
            if (flipped[c])
                assert(a[0] == b[0] && a[1] == b[1] && a[2] == b[4] && a[3] == b[5] && a[4] == b[2] && a[5] == b[3]);
            else
                assert(!memcmp(a, b, 6 * sizeof(float)));
        }
        for (int v = 0; v < 8; ++v)
            for (int k = 0; k < 3; ++k) {
                const size_t i = 3 * (size_t)(8 * c + v) + (size_t)k;
                assert(m.normals[i] == (flipped[c] ? -before.normals[i] : before.normals[i]));
            }
        base += count;
    }
    printf("  %-44s components %u, closed %u, reoriented %u (%u faces)\n", name, o.components, o.closed_components,
           o.reoriented_components, o.reoriented_faces);
    assert(o.components == (uint32_t)n);
    assert(o.reoriented_components == want_flips && o.reoriented_faces == want_faces);
    if (want_closed != UINT32_MAX)
        assert(o.closed_components == want_closed);
    free(before.normals);
    free(before.corner_uvs);
    meso_mesh_free(&m);
}

static void test_outward_cube_untouched(void)
{
    const cube c[1] = {{{0, 0, 0}, 1, 0, 0}};
    run("outward cube: untouched", c, 1, (const int[]){0}, UINT32_MAX);
}

static void test_inward_cube_flipped(void)
{
    const cube c[1] = {{{5, -3, 2}, 2, 1, 0}};
    run("inward cube: flipped", c, 1, (const int[]){1}, 1);
}

static void test_separate_solids_judged_each(void)
{
    /* A large correct cube and a small inverted one beside it: the summed
     * volume is positive, but the small one is inside-out. */
    const cube c[2] = {{{0, 0, 0}, 10, 0, 0}, {{20, 0, 0}, 1, 1, 0}};
    run("two solids, the small one inward: it flips", c, 2, (const int[]){0, 1}, 2);
}

static void test_cavity_kept(void)
{
    /* A hollow cube: outer facing out, inner (the cavity) facing in. */
    const cube c[2] = {{{0, 0, 0}, 4, 0, 0}, {{1, 1, 1}, 2, 1, 0}};
    run("hollow cube (cavity faces in): untouched", c, 2, (const int[]){0, 0}, UINT32_MAX);
}

static void test_inside_out_hollow_flipped_whole(void)
{
    /* The same hollow cube inside-out: outer in, cavity out. Both flip. */
    const cube c[2] = {{{1, 1, 1}, 2, 0, 0}, {{0, 0, 0}, 4, 1, 0}};
    run("inside-out hollow cube: both flip", c, 2, (const int[]){1, 1}, 2);
}

static void test_island_in_cavity(void)
{
    /* Outer out, cavity in, an island inside the cavity inverted: only the
     * island flips (even depth, negative volume). */
    const cube c[3] = {{{0, 0, 0}, 8, 0, 0}, {{1, 1, 1}, 6, 1, 0}, {{3, 3, 3}, 2, 1, 0}};
    run("island in a cavity, inverted: only it flips", c, 3, (const int[]){0, 0, 1}, 3);
}

static void test_nested_outward_left_alone(void)
{
    /* A negative component elsewhere triggers the nesting pass; a positive
     * cube inside a positive cube (odd depth, container not flipped) stays. */
    const cube c[3] = {{{0, 0, 0}, 4, 0, 0}, {{1, 1, 1}, 2, 0, 0}, {{10, 0, 0}, 1, 1, 0}};
    run("outward cube in outward cube: both stay", c, 3, (const int[]){0, 0, 1}, 3);
}

static void test_open_inward_untouched(void)
{
    /* An inverted cube with a hole has no volume sign: left alone. */
    const cube c[1] = {{{0, 0, 0}, 1, 1, 1}};
    run("inward cube with a hole: untouched", c, 1, (const int[]){0}, 0);
}

int main(void)
{
    test_outward_cube_untouched();
    test_inward_cube_flipped();
    test_separate_solids_judged_each();
    test_cavity_kept();
    test_inside_out_hollow_flipped_whole();
    test_island_in_cavity();
    test_nested_outward_left_alone();
    test_open_inward_untouched();
    printf("test_mesh_orient: all passed\n");
    return 0;
}
