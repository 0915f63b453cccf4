/*
 * rt_prism_walk.c — the prisms' side neighbours, for one hull fragment a
 * pixel (issue 14: "Work per pixel follows what is seen").
 *
 * With hull rejection every prism rasterised its entry faces: its caps and
 * its three sides, so a pixel over a smooth shell got one fragment for
 * every prism its ray crossed (9.2 a covered pixel at Table 1's reference
 * setup), 7.2 of them stopped by the hit image at about 1 µs each on
 * llvmpipe (tests/bench/results/lod_scene.csv: two thirds of the nearest
 * shell's time). A side two prisms share is crossed from one prism into
 * the other, never from outside the shell, so with the walk
 * (shell_frag.glsl, smooth shells) such sides are not rasterised: a
 * fragment comes from the boundary of the shell's volume alone (the top
 * caps, the bottom caps and the sides on the mesh's boundary), and when its
 * ray leaves the prism through a shared side without a hit, the march goes
 * on in the neighbour across that side.
 *
 * Decisions:
 *  - Neighbours share an edge of the base mesh, found on vertices that are
 *    the same prism corners: equal base position and equal directors (all
 *    layers), bit for bit. So a uv seam (vertices split for their texture
 *    coordinates) is walked across, as the shell's geometry there is one
 *    surface; each prism still maps its own texture coordinates.
 *  - An edge of one triangle, or of three or more, is a boundary: both
 *    sides draw their side faces, as every side did before. So is an edge
 *    of a folded prism (prism_regular): prisms that overlap do not hand a
 *    ray from one to the other at their shared side (measured: the wingnut
 *    of tests/gl/test_rt_shell.c, directors along the normals, lost 34
 *    pixels of 3588 before this rule).
 *  - Where the ray leaves a prism is found exactly (shell_frag.glsl
 *    exit_side: the ray against the three bilinear sides and the two
 *    caps), not from the march's chord, which bends in texture space: with
 *    the chord, a bake of spot (Lp-averaged directors, its sides twisted)
 *    lost 11 of 1632 pixels of tests/gl/test_rt_instances.c's view. Two
 *    fallbacks: a fragment rasterised on a cap whose ray misses the prism
 *    (it grazes the edge two caps share) goes to the neighbour across the
 *    edge nearest the ray (grazed_side), and where rounding leaves no
 *    crossing at all, the chord's side is taken. Measured against the
 *    draws without the walk on that bake (test_rt_shell_reject.c): 11 of
 *    4613 pixels differ, 10 of them nearer (test_rt_shell_baked.c finds the
 *    walk's images as close to the exact reference as before, or closer)
 *    and 1 a hole.
 *  - side k is the edge from corner k to corner k + 1 (mod 3), the side
 *    hull_face numbers (shell_common.glsl); neighbour[3 t + k] is the
 *    triangle across it, -1 for none.
 *  - The bottom caps: a ray from outside enters the shell through them
 *    only from what the base mesh encloses, most of what was still
 *    rejected (0.81 fragments a covered pixel at Table 1's reference
 *    setup: the far side's inner caps, behind the hit). They are left out
 *    (shell_vert.glsl u_no_bottom, rt_shell.c) when no ray can get there
 *    without a hit: the shell is closed (`closed`: every edge of the welded
 *    mesh has two triangles), so a ray gets inside only across a bottom
 *    cap, at w = 0 of that prism; its texture function is a height field or
 *    none, solid at w = 0 everywhere (shell_texfn.glsl solid: w <= h, h >=
 *    0; the march takes w < 0 as solid too, so a step across w = 0 hits),
 *    so the march there hits first; and the box of the prisms' corners
 *    lies wholly beyond the near plane (rt_shell.c box_reaches_near), so
 *    every ray starts outside it, and outside what the caps enclose (an eye
 *    inside the box has corners behind it, on the near plane's eye side).
 *    A volume may be empty at w = 0: its bottom caps are always drawn.
 *  - meso_rt_shell_update: a prism may fold, or unfold, with the shape, so
 *    the folding is tested again (once a prism, not per shared side). The
 *    weld is kept while every pair of neighbours still shares its side's
 *    corners bit for bit (mesoi_prism_topology_holds, one pass), and found
 *    again (a sort) when a pair no longer does: a shape that moves a seam's
 *    split vertices apart opens a crack no ray may walk across
 *    (test_rt_shell_reject.c "cracked seam"). Corners that come together
 *    only after the load are not welded until a pair breaks: their sides
 *    stay drawn, which is correct, only less walked. Measured on spot_uv
 *    (5856 prisms, tests/bench/bench_anim_update.c): 0.42-0.46 ms an update,
 *    against 2.2-2.9 ms welding again every time and 2.7 ms before, when
 *    the folding was tested for both prisms of every side.
 *  - The shaders see the prisms in the order they are drawn (order_buf,
 *    rt_shell.c order_prisms), so the neighbours go up in that order too:
 *    adj_buf holds, per drawn slot, the slots of its neighbours. A prism
 *    not drawn (a parts draw's subset, rt_parts.c: the rest is drawn by
 *    stand-in patches) has no slot, so the walk stops at it and the side
 *    is drawn.
 */
#include "rt_internal.h"

#include <stdlib.h>
#include <string.h>

typedef struct corner_key {
    float v[9]; /* bottom position, top director, second-layer director */
    uint32_t vertex;
} corner_key;

static int by_corner(const void* pa, const void* pb)
{
    const corner_key *a = pa, *b = pb;
    const int c = memcmp(a->v, b->v, sizeof a->v);
    if (c)
        return c;
    return a->vertex < b->vertex ? -1 : a->vertex > b->vertex;
}

typedef struct edge_key {
    uint32_t lo, hi; /* welded vertex ids, lo < hi */
    uint32_t slot;   /* 3 * triangle + side */
} edge_key;

static int by_edge(const void* pa, const void* pb)
{
    const edge_key *a = pa, *b = pb;
    if (a->lo != b->lo)
        return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi)
        return a->hi < b->hi ? -1 : 1;
    return a->slot < b->slot ? -1 : a->slot > b->slot;
}

/* Whether triangle t's prism is a proper slab: every director on the base
 * triangle's outer side and the triangle T(w) = b + w n keeping its
 * orientation at w = 1/4 .. 1 (the sides' walk assumes that the prisms
 * tile the shell; a folded prism overlaps its neighbours). */
static int prism_regular(const mesoi_shell* s, uint32_t t)
{
    const size_t nv = s->vertex_count;
    double b[3][3], n[3][3];
    for (int c = 0; c < 3; ++c) {
        const size_t v = s->indices[3 * (size_t)t + (size_t)c];
        if (v >= nv)
            return 0;
        for (int k = 0; k < 3; ++k) { /* fill_vertex_texels' bottom and top */
            const double d1 = s->layers == 2 ? s->directors[3 * (nv + v) + (size_t)k] : 0.0;
            b[c][k] = s->positions[3 * v + (size_t)k] + d1;
            n[c][k] = s->positions[3 * v + (size_t)k] + s->directors[3 * v + (size_t)k] - b[c][k];
        }
    }
    double n0[3] = {0, 0, 0};
    for (int step = 0; step <= 4; ++step) {
        const double w = step / 4.0;
        double p[3][3], e1[3], e2[3], nw[3];
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                p[c][k] = b[c][k] + w * n[c][k];
        for (int k = 0; k < 3; ++k) {
            e1[k] = p[1][k] - p[0][k];
            e2[k] = p[2][k] - p[0][k];
        }
        nw[0] = e1[1] * e2[2] - e1[2] * e2[1];
        nw[1] = e1[2] * e2[0] - e1[0] * e2[2];
        nw[2] = e1[0] * e2[1] - e1[1] * e2[0];
        if (step == 0) {
            memcpy(n0, nw, sizeof n0);
            for (int c = 0; c < 3; ++c)
                if (!(n[c][0] * n0[0] + n[c][1] * n0[1] + n[c][2] * n0[2] > 0.0))
                    return 0;
        } else if (!(nw[0] * n0[0] + nw[1] * n0[1] + nw[2] * n0[2] > 0.0)) {
            return 0;
        }
    }
    return 1;
}

/* A vertex's corner key: bottom position, top director, second-layer
 * director (+0.0f: -0 and 0 are one point). */
static void corner_of(const mesoi_shell* s, uint32_t v, float key[9])
{
    const size_t nv = s->vertex_count;
    memset(key, 0, sizeof(float) * 9);
    for (int k = 0; k < 3; ++k) {
        key[k] = s->positions[3 * (size_t)v + k] + 0.0f;
        key[3 + k] = s->directors[3 * (size_t)v + k] + 0.0f;
        if (s->layers == 2)
            key[6 + k] = s->directors[3 * (nv + v) + k] + 0.0f;
    }
}

meso_result mesoi_prism_topology(meso_rt* rt, const mesoi_shell* s, int32_t* mates, int* closed)
{
    const uint32_t nv = s->vertex_count, nt = s->triangle_count;
    corner_key* ck = mesoi_rt_alloc(rt, sizeof(corner_key) * (nv ? nv : 1));
    uint32_t* weld = mesoi_rt_alloc(rt, sizeof(uint32_t) * (nv ? nv : 1));
    edge_key* ek = mesoi_rt_alloc(rt, sizeof(edge_key) * 3 * (size_t)(nt ? nt : 1));
    if (!ck || !weld || !ek) {
        mesoi_rt_free(rt, ck);
        mesoi_rt_free(rt, weld);
        mesoi_rt_free(rt, ek);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    for (uint32_t v = 0; v < nv; ++v) {
        corner_of(s, v, ck[v].v);
        ck[v].vertex = v;
    }
    qsort(ck, nv, sizeof(corner_key), by_corner);
    for (uint32_t i = 0; i < nv; ++i)
        weld[ck[i].vertex] = i > 0 && !memcmp(ck[i].v, ck[i - 1].v, sizeof ck[i].v) ? weld[ck[i - 1].vertex]
                                                                                     : ck[i].vertex;
    uint32_t ne = 0;
    *closed = 1;
    for (uint32_t t = 0; t < nt; ++t)
        for (uint32_t k = 0; k < 3; ++k) {
            mates[3 * (size_t)t + k] = -1;
            const uint32_t i = s->indices[3 * (size_t)t + k], j = s->indices[3 * (size_t)t + (k + 1) % 3];
            if (i >= nv || j >= nv) {
                *closed = 0;
                continue;
            }
            const uint32_t a = weld[i], b = weld[j];
            if (a == b) {
                *closed = 0;
                continue; /* a side without width: nothing to cross */
            }
            ek[ne].lo = a < b ? a : b;
            ek[ne].hi = a < b ? b : a;
            ek[ne++].slot = 3 * t + k;
        }
    qsort(ek, ne, sizeof(edge_key), by_edge);
    for (uint32_t i = 0; i < ne;) {
        uint32_t j = i + 1;
        while (j < ne && ek[j].lo == ek[i].lo && ek[j].hi == ek[i].hi)
            ++j;
        if (j - i != 2)
            *closed = 0;
        if (j - i == 2 && ek[i].slot / 3 != ek[i + 1].slot / 3) {
            mates[ek[i].slot] = (int32_t)ek[i + 1].slot;
            mates[ek[i + 1].slot] = (int32_t)ek[i].slot;
        }
        i = j;
    }
    mesoi_rt_free(rt, ck);
    mesoi_rt_free(rt, weld);
    mesoi_rt_free(rt, ek);
    return MESO_OK;
}

/* Whether vertices a and b are one prism corner (corner_of's keys equal). */
static int same_corner(const mesoi_shell* s, uint32_t a, uint32_t b)
{
    if (a == b)
        return 1;
    const size_t nv = s->vertex_count;
    for (int k = 0; k < 3; ++k) {
        /* +0.0f: -0 and 0 are one point; bit for bit otherwise (NaN too) */
        const float pa = s->positions[3 * (size_t)a + k] + 0.0f, pb = s->positions[3 * (size_t)b + k] + 0.0f;
        const float da = s->directors[3 * (size_t)a + k] + 0.0f, db = s->directors[3 * (size_t)b + k] + 0.0f;
        if (memcmp(&pa, &pb, sizeof pa) || memcmp(&da, &db, sizeof da))
            return 0;
        if (s->layers == 2) {
            const float ea = s->directors[3 * (nv + a) + k] + 0.0f, eb = s->directors[3 * (nv + b) + k] + 0.0f;
            if (memcmp(&ea, &eb, sizeof ea))
                return 0;
        }
    }
    return 1;
}

int mesoi_prism_topology_holds(const mesoi_shell* s, const int32_t* mates)
{
    const uint32_t nt = s->triangle_count;
    for (uint32_t e = 0; e < 3 * nt; ++e) {
        const int32_t f = mates[e];
        if (f < 0 || (uint32_t)f < e)
            continue; /* none, or the pair checked from its other side */
        const uint32_t t = e / 3, k = e % 3, u = (uint32_t)f / 3, m = (uint32_t)f % 3;
        const uint32_t i = s->indices[3 * t + k], j = s->indices[3 * t + (k + 1) % 3];
        const uint32_t c = s->indices[3 * u + m], d = s->indices[3 * u + (m + 1) % 3];
        /* the two sides' corners still one, either way round, and apart */
        if (same_corner(s, i, j) ||
            !((same_corner(s, i, d) && same_corner(s, j, c)) || (same_corner(s, i, c) && same_corner(s, j, d))))
            return 0;
    }
    return 1;
}

meso_result mesoi_prism_neighbours(meso_rt* rt, const mesoi_shell* s, const int32_t* mates, int32_t* out)
{
    const uint32_t nt = s->triangle_count;
    uint8_t* regular = mesoi_rt_alloc(rt, nt ? nt : 1);
    if (!regular)
        return MESO_ERR_OUT_OF_MEMORY;
    for (uint32_t t = 0; t < nt; ++t)
        regular[t] = (uint8_t)prism_regular(s, t);
    for (size_t i = 0; i < 3 * (size_t)nt; ++i)
        out[i] = mates[i] >= 0 && regular[i / 3] && regular[mates[i] / 3] ? mates[i] / 3 : -1;
    mesoi_rt_free(rt, regular);
    return MESO_OK;
}
