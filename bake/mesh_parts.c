/*
 * mesh_parts.c — a mesh cut into parts with levels of their own
 * (mesh_parts.h, FORMAT.md §7.11; issue 14, Deliver 3: "each part ...
 * draws the coarsest level whose projected error is ≤ τ; neighbouring
 * parts may differ by at most one level and never crack").
 *
 * Whole-object levels make a long or near object pay for its finest level
 * everywhere once any of it is near. Parts let the near end be fine and
 * the far end coarse. How, and what was decided where the sources leave
 * it open (notes/lod-anchors.md: meshoptimizer's cluster-LOD demo and
 * Nanite build a DAG of cluster groups whose borders move between levels;
 * this is the simpler scheme the demo starts from):
 *
 * - The cut: triangles split recursively in two at the median of their
 *   centroids along the longest side of the centroids' box (ties by
 *   triangle index, so the cut is deterministic), until a part has at most
 *   `part_triangles` (between half and all of it). Within a part the
 *   triangles keep the input's order.
 * - Each part is simplified alone, with mesh_levels.c's chain (halving,
 *   the same seam weld, errors measured against the part's level 0 by
 *   surface_distance.c) and meshopt_SimplifyLockBorder: every vertex on
 *   the part's border (an edge of one triangle of the part, after the
 *   seam weld) keeps its place at every level, so every border edge stays
 *   an edge; and each level's border (its edges used an odd number of
 *   times) is checked against level 0's, the chain ending before the
 *   first level where it differs (meshopt 0.18 did move one on
 *   spot_uv.obj). Two neighbouring parts therefore share the same border
 *   polyline at any pair of levels: no crack, whatever levels a reader
 *   picks (tests/unit/test_mesh_parts.c checks the union's edges for
 *   random picks). The cost is that a part cannot get coarser than its
 *   border: its chain stops where a halving keeps more than 85 % of the
 *   triangles, as mesh_levels.c's does.
 * - Neighbours: two parts that share a vertex position (after the weld, a
 *   seam is no border). A reader keeps neighbours within one level of
 *   each other (FORMAT.md §7.11); nothing here depends on it.
 * - The input is not cut below 2 * part_triangles triangles: a part as
 *   large as the object saves nothing.
 */
#include "mesh_parts.h"

#include <stdlib.h>
#include <string.h>

#if MESO_HAVE_MESHOPTIMIZER
#include <meshoptimizer.h>
#endif

#include "mesh_levels.h"

void meso_mesh_parts_free(meso_mesh_parts* p)
{
    if (!p)
        return;
    for (uint32_t i = 0; p->part && i < p->count; ++i) {
        for (uint32_t l = 0; p->part[i].level && l < p->part[i].level_count; ++l)
            meso_mesh_free(&p->part[i].level[l].mesh);
        free(p->part[i].level);
    }
    free(p->part);
    free(p->edges);
    free(p->part_of);
    memset(p, 0, sizeof(*p));
}

#if MESO_HAVE_MESHOPTIMIZER

typedef struct key {
    float c;
    uint32_t t;
} key;

static int by_key(const void* a, const void* b)
{
    const key *x = a, *y = b;
    if (x->c != y->c)
        return x->c < y->c ? -1 : 1;
    return x->t < y->t ? -1 : x->t > y->t;
}

static int by_u64(const void* a, const void* b)
{
    const uint64_t x = *(const uint64_t*)a, y = *(const uint64_t*)b;
    return x < y ? -1 : x > y;
}

static int by_pair(const void* a, const void* b)
{
    const uint32_t *x = a, *y = b;
    if (x[0] != y[0])
        return x[0] < y[0] ? -1 : 1;
    return x[1] < y[1] ? -1 : x[1] > y[1];
}

/* Parts of tris[0..n): part_of[t] for each, numbered in order. */
static void cut(const float* centroid, uint32_t* tris, uint32_t n, uint32_t target, key* keys, uint32_t* part_of,
                uint32_t* parts)
{
    if (n <= target) {
        for (uint32_t i = 0; i < n; ++i)
            part_of[tris[i]] = *parts;
        ++*parts;
        return;
    }
    float lo[3], hi[3];
    for (int k = 0; k < 3; ++k)
        lo[k] = hi[k] = centroid[3 * (size_t)tris[0] + (size_t)k];
    for (uint32_t i = 1; i < n; ++i)
        for (int k = 0; k < 3; ++k) {
            const float c = centroid[3 * (size_t)tris[i] + (size_t)k];
            lo[k] = c < lo[k] ? c : lo[k];
            hi[k] = c > hi[k] ? c : hi[k];
        }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (hi[k] - lo[k] > hi[axis] - lo[axis])
            axis = k;
    for (uint32_t i = 0; i < n; ++i)
        keys[i] = (key){centroid[3 * (size_t)tris[i] + (size_t)axis], tris[i]};
    qsort(keys, n, sizeof(key), by_key);
    for (uint32_t i = 0; i < n; ++i)
        tris[i] = keys[i].t;
    cut(centroid, tris, n / 2, target, keys, part_of, parts);
    cut(centroid, tris + n / 2, n - n / 2, target, keys, part_of, parts);
}

/* Pairs of parts whose triangles share a vertex position. */
static meso_result neighbours(const meso_mesh* m, const uint32_t* part_of, meso_mesh_parts* out)
{
    const size_t nc = 3 * (size_t)m->triangle_count;
    uint32_t* remap = malloc(sizeof(uint32_t) * (m->vertex_count ? m->vertex_count : 1));
    uint32_t* vp = malloc(sizeof(uint32_t) * 2 * nc); /* (welded vertex, part) per corner */
    meso_result r = remap && vp ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    size_t np = 0, ne = 0, cap = 0;
    uint32_t* edges = NULL;
    if (r == MESO_OK) {
        meshopt_generateVertexRemap(remap, NULL, m->vertex_count, m->positions, m->vertex_count, 3 * sizeof(float));
        for (size_t c = 0; c < nc; ++c) {
            vp[2 * c] = remap[m->indices[c]];
            vp[2 * c + 1] = part_of[c / 3];
        }
        qsort(vp, nc, 2 * sizeof(uint32_t), by_pair);
        for (size_t c = 0; c < nc; ++c) /* unique */
            if (np == 0 || vp[2 * c] != vp[2 * np - 2] || vp[2 * c + 1] != vp[2 * np - 1]) {
                vp[2 * np] = vp[2 * c];
                vp[2 * np + 1] = vp[2 * c + 1];
                ++np;
            }
    }
    for (size_t a = 0; r == MESO_OK && a < np;) {
        size_t b = a;
        while (b < np && vp[2 * b] == vp[2 * a])
            ++b;
        for (size_t i = a; r == MESO_OK && i < b; ++i)
            for (size_t j = i + 1; j < b; ++j) {
                if (ne == cap) {
                    cap = cap ? 2 * cap : 256;
                    uint32_t* grown = realloc(edges, sizeof(uint32_t) * 2 * cap);
                    if (!grown) {
                        r = MESO_ERR_OUT_OF_MEMORY;
                        break;
                    }
                    edges = grown;
                }
                edges[2 * ne] = vp[2 * i + 1]; /* parts ascending within a vertex */
                edges[2 * ne + 1] = vp[2 * j + 1];
                ++ne;
            }
        a = b;
    }
    if (r == MESO_OK && ne) {
        qsort(edges, ne, 2 * sizeof(uint32_t), by_pair);
        size_t u = 0;
        for (size_t e = 0; e < ne; ++e)
            if (u == 0 || edges[2 * e] != edges[2 * u - 2] || edges[2 * e + 1] != edges[2 * u - 1]) {
                edges[2 * u] = edges[2 * e];
                edges[2 * u + 1] = edges[2 * e + 1];
                ++u;
            }
        ne = u;
    }
    free(remap);
    free(vp);
    if (r != MESO_OK) {
        free(edges);
        return r;
    }
    out->edges = edges;
    out->edge_count = (uint32_t)ne;
    return MESO_OK;
}

/* >>border check: the edges of `pm` used an odd number of times (its
 * border, mod 2), each as its two end positions (the lesser, by bytes,
 * first), sorted by bytes. Positions are welded as everywhere else here,
 * by meshopt_generateVertexRemap (bitwise equal positions are one vertex),
 * and the edges are kept as positions so that two levels, whose vertex
 * numbers differ, compare directly. */
typedef struct edge_key {
    float p[6];
} edge_key;

static int by_edge(const void* a, const void* b)
{
    return memcmp(a, b, sizeof(edge_key));
}

static edge_key* border_of(const meso_mesh* pm, size_t* count)
{
    const size_t ne = 3 * (size_t)pm->triangle_count, nv = pm->vertex_count ? pm->vertex_count : 1;
    uint32_t* remap = malloc(sizeof(uint32_t) * nv);
    float* wpos = malloc(sizeof(float) * 3 * nv); /* a welded id's position */
    uint64_t* e = malloc(sizeof(uint64_t) * (ne ? ne : 1));
    edge_key* out = malloc(sizeof(edge_key) * (ne ? ne : 1));
    size_t n = 0;
    if (remap && wpos && e && out) {
        meshopt_generateVertexRemap(remap, NULL, pm->vertex_count, pm->positions, pm->vertex_count,
                                    3 * sizeof(float));
        for (uint32_t v = 0; v < pm->vertex_count; ++v)
            memcpy(wpos + 3 * (size_t)remap[v], pm->positions + 3 * (size_t)v, 3 * sizeof(float));
        for (size_t c = 0; c < ne; ++c) {
            const uint64_t a = remap[pm->indices[c]], b = remap[pm->indices[(c / 3) * 3 + (c % 3 + 1) % 3]];
            e[c] = a < b ? a << 32 | b : b << 32 | a;
        }
        qsort(e, ne, sizeof(uint64_t), by_u64);
        for (size_t i = 0; i < ne;) {
            size_t j = i;
            while (j < ne && e[j] == e[i])
                ++j;
            if ((j - i) & 1) {
                const float *pa = wpos + 3 * (size_t)(e[i] >> 32), *pb = wpos + 3 * (size_t)(e[i] & 0xffffffffu);
                const int swap = memcmp(pa, pb, 3 * sizeof(float)) > 0;
                memcpy(out[n].p, swap ? pb : pa, 3 * sizeof(float));
                memcpy(out[n].p + 3, swap ? pa : pb, 3 * sizeof(float));
                ++n;
            }
            i = j;
        }
        qsort(out, n, sizeof(edge_key), by_edge);
    } else {
        free(out);
        out = NULL;
    }
    free(remap);
    free(wpos);
    free(e);
    *count = n;
    return out;
}

/* The number of levels of `P` whose border is level 0's: a level whose
 * simplification moved the border (meshopt 0.18 still collapsed a border
 * vertex of a part of spot_uv.obj with meshopt_SimplifyLockBorder, found
 * by tests/unit/test_mesh_parts.c) ends the chain there, so any choice of
 * levels meets its neighbours edge to edge. */
static uint32_t levels_keeping_border(const meso_mesh_part* P, int* oom)
{
    size_t n0 = 0;
    edge_key* b0 = border_of(&P->level[0].mesh, &n0);
    uint32_t keep = 1;
    for (uint32_t l = 1; b0 && l < P->level_count && keep == l; ++l) {
        size_t nl = 0;
        edge_key* bl = border_of(&P->level[l].mesh, &nl);
        if (!bl) {
            free(b0);
            *oom = 1;
            return keep;
        }
        if (nl == n0 && memcmp(bl, b0, sizeof(edge_key) * n0) == 0)
            keep = l + 1;
        free(bl);
    }
    *oom = !b0;
    free(b0);
    return keep;
}

static meso_result build(const meso_mesh* m, const meso_mesh_parts_options* o, meso_mesh_parts* out,
                         meso_error* err)
{
    const uint32_t nt = m->triangle_count;
    uint32_t target = o->part_triangles ? o->part_triangles : MESO_MESH_PARTS_TRIANGLES;
    if (nt / MESO_MESH_PARTS_MAX + 1 > target)
        target = nt / MESO_MESH_PARTS_MAX + 1;
    if (nt < 2 * target)
        return MESO_OK; /* not cut */
    float* centroid = malloc(sizeof(float) * 3 * nt);
    uint32_t* tris = malloc(sizeof(uint32_t) * nt);
    uint32_t* part_of = malloc(sizeof(uint32_t) * nt);
    uint32_t* corners = malloc(sizeof(uint32_t) * 3 * nt);
    key* keys = malloc(sizeof(key) * nt);
    meso_result r = centroid && tris && part_of && corners && keys ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    uint32_t parts = 0;
    if (r == MESO_OK) {
        for (uint32_t t = 0; t < nt; ++t) {
            tris[t] = t;
            for (int k = 0; k < 3; ++k) {
                double c = 0.0;
                for (int j = 0; j < 3; ++j)
                    c += m->positions[3 * (size_t)m->indices[3 * (size_t)t + (size_t)j] + (size_t)k];
                centroid[3 * (size_t)t + (size_t)k] = (float)(c / 3.0);
            }
        }
        cut(centroid, tris, nt, target, keys, part_of, &parts);
        out->part = calloc(parts, sizeof(meso_mesh_part));
        r = out->part ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r == MESO_OK) {
        out->count = parts;
        r = neighbours(m, part_of, out);
    }
    /* Each part's triangles in the input's order, then its chain. */
    for (uint32_t p = 0; r == MESO_OK && p < parts; ++p) {
        uint32_t n = 0;
        for (uint32_t t = 0; t < nt; ++t)
            if (part_of[t] == p) {
                memcpy(corners + 3 * (size_t)n, m->indices + 3 * (size_t)t, 3 * sizeof(uint32_t));
                ++n;
            }
        meso_mesh_part* P = &out->part[p];
        meso_mesh base;
        if ((r = meso_mesh_subset(m, corners, n, &base)) != MESO_OK)
            break;
        const meso_mesh_levels_options lo = {
            .max_levels = o->max_levels, .threads = o->threads, .lock_border = 1, .min_triangles = 32};
        meso_mesh_level* lv = NULL;
        uint32_t nlv = 0;
        r = meso_mesh_levels_build(&base, &lo, &lv, &nlv, err);
        P->level = r == MESO_OK ? calloc(nlv + 1, sizeof(meso_mesh_part_level)) : NULL;
        if (r == MESO_OK && !P->level)
            r = MESO_ERR_OUT_OF_MEMORY;
        if (r != MESO_OK) {
            meso_mesh_free(&base);
            meso_mesh_levels_free(lv, nlv);
            break;
        }
        P->level_count = nlv + 1;
        P->level[0].mesh = base;
        meso_mesh_bounds(&base, P->level[0].bbox_min, P->level[0].bbox_max);
        for (uint32_t l = 0; l < nlv; ++l) {
            P->level[l + 1].mesh = lv[l].mesh; /* moved */
            P->level[l + 1].error = lv[l].error;
            memcpy(P->level[l + 1].bbox_min, lv[l].bbox_min, sizeof(lv[l].bbox_min));
            memcpy(P->level[l + 1].bbox_max, lv[l].bbox_max, sizeof(lv[l].bbox_max));
            memset(&lv[l].mesh, 0, sizeof(lv[l].mesh));
        }
        meso_mesh_levels_free(lv, nlv);
        int oom = 0;
        const uint32_t keep = levels_keeping_border(P, &oom);
        if (oom) {
            r = MESO_ERR_OUT_OF_MEMORY;
            break;
        }
        for (uint32_t l = keep; l < P->level_count; ++l)
            meso_mesh_free(&P->level[l].mesh);
        P->level_count = keep;
    }
    free(centroid);
    free(tris);
    out->part_of = part_of;
    free(corners);
    free(keys);
    if (r == MESO_ERR_OUT_OF_MEMORY)
        r = meso_bake_fail(err, r, 0, "mesh parts: out of memory");
    return r;
}
#endif /* MESO_HAVE_MESHOPTIMIZER */

meso_result meso_mesh_parts_build(const meso_mesh* m, const meso_mesh_parts_options* o, meso_mesh_parts* out,
                                  meso_error* err)
{
    memset(out, 0, sizeof(*out));
    const meso_mesh_parts_options defaults = {0};
    if (!o)
        o = &defaults;
    if (!m || m->triangle_count == 0)
        return MESO_OK;
#if MESO_HAVE_MESHOPTIMIZER
    return build(m, o, out, err);
#else
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "mesh parts need meshoptimizer: this build has none");
#endif
}
