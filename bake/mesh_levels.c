/*
 * mesh_levels.c — levels of detail of a triangle mesh (mesh_levels.h):
 * meshoptimizer's edge-collapse simplifier (meshopt_simplify, Debian's
 * libmeshoptimizer-dev 0.18, its C API) in a chain, each level's error
 * measured against level 0 by surface_distance.c. Issue 14; the chain's
 * rules are those of meshoptimizer's cluster-LOD demo (notes/lod-anchors.md):
 *
 * - each level asks for half the previous level's triangles, simplified
 *   from the previous level (the demo's chain; cheaper than from level 0
 *   each time, and the running-max error below is what a chain needs);
 * - a level that keeps more than 85 % of the previous one's triangles is
 *   terminal: it is dropped and the chain stops (the demo's rule for
 *   groups that cannot simplify);
 * - no level is made from one of at most 256 triangles, and there are at
 *   most 8 levels (level 0 included);
 * - of the faces meshopt leaves twice on the same vertices the first stays
 *   (drop_duplicate_faces);
 * - meshopt's own error target is left open (1.0 = the whole extent): the
 *   count is the target, the error is measured afterwards, not predicted.
 *   meshopt_SimplifyLockBorder is passed only for a part of a mesh
 *   (mesh_parts.c: its border is shared with the next part); an open
 *   mesh's border is simplified like the rest, and the measured error says
 *   what it cost.
 *
 * Seams. An importer that splits vertices at uv or normal seams (same
 * position, other attributes) leaves the simplifier vertices that look like
 * borders or worse. Measured with 0.18 on a 64 × 32 UV sphere (3968
 * triangles) whose vertices are split around every K × K block of quads:
 * one seam (K = 64) still halves, since 0.18 pairs seam vertices with
 * equal positions itself; but where three or more copies of a position meet
 * it locks the vertex, so K = 1 (every quad split) gives no level at all,
 * K = 2 stops at 3072 triangles, K = 8 at 384. Welding only the index
 * buffer (meshopt_generateShadowIndexBuffer) does not help in 0.18: the
 * simplifier builds its own position remap over every vertex of the buffer,
 * the unused copies included, and locks the same vertices. So the chain
 * runs on a compact welded copy (meshopt_generateVertexRemap over the
 * positions alone: one vertex per position), where a seam is an ordinary
 * edge, and each simplified triangle is mapped back to original vertices,
 * which keep their own normals and uvs: for each corner among the copies of
 * its position, the combination of copies whose uvs are closest together
 * (the triangle stays inside one uv chart), or without uvs whose normals
 * are closest to the triangle's face normal; the lowest index on ties.
 * `split_seams` = 1 skips the weld (the tests show what it changes).
 *
 * Draco (mesobake mesh --draco) encodes every level with the same bits, at
 * most MESO_DRACO_MAX_BITS (meso_bake.h: Draco 1.5.5's entropy table spans
 * the whole quantised range; at 29-30 bits the sphere's levels took minutes).
 *
 * Normals of a coarse level: each vertex keeps its own (the level's
 * vertices are level 0's). Recomputing them from the coarse triangles would
 * flatten smooth shading that the input's normals carry; the coarse level is
 * drawn only where its geometric error is below the pixel budget anyway.
 */
#include "mesh_levels.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#if MESO_HAVE_MESHOPTIMIZER
#include <meshoptimizer.h>
#endif

#include "surface_distance.h"

void meso_mesh_levels_free(meso_mesh_level* levels, uint32_t count)
{
    for (uint32_t i = 0; levels && i < count; ++i)
        meso_mesh_free(&levels[i].mesh);
    free(levels);
}

#if MESO_HAVE_MESHOPTIMIZER

/* The original vertices of each welded vertex: copies[start[w] ..
 * start[w + 1]), ascending (only vertices some triangle uses). */
typedef struct weld_map {
    uint32_t* start;
    uint32_t* copies;
} weld_map;

static double uv_gap(const float* uvs, uint32_t a, uint32_t b)
{
    const double du = (double)uvs[2 * (size_t)a] - uvs[2 * (size_t)b];
    const double dv = (double)uvs[2 * (size_t)a + 1] - uvs[2 * (size_t)b + 1];
    return sqrt(du * du + dv * dv);
}

/* How badly the copies (c[0], c[1], c[2]) fit one triangle of face normal
 * `fn`: the uv perimeter when there are uvs, else how far the normals turn
 * from the face's. */
static double corner_cost(const meso_mesh* m, const uint32_t c[3], const double fn[3])
{
    if (m->uvs)
        return uv_gap(m->uvs, c[0], c[1]) + uv_gap(m->uvs, c[1], c[2]) + uv_gap(m->uvs, c[2], c[0]);
    double cost = 0;
    for (int k = 0; m->normals && k < 3; ++k) {
        const float* n = m->normals + 3 * (size_t)c[k];
        cost += 1.0 - (n[0] * fn[0] + n[1] * fn[1] + n[2] * fn[2]);
    }
    return cost;
}

/* Original-vertex corners for a welded triangle (w[3]) of the level. */
static void pick_copies(const meso_mesh* m, const weld_map* wm, const uint32_t w[3], uint32_t out[3])
{
    const uint32_t* cp[3];
    uint32_t n[3];
    for (int k = 0; k < 3; ++k) {
        cp[k] = wm->copies + wm->start[w[k]];
        n[k] = wm->start[w[k] + 1] - wm->start[w[k]];
        out[k] = cp[k][0];
    }
    if (n[0] * n[1] * n[2] == 1 || (!m->uvs && !m->normals))
        return;
    double fn[3] = {0, 0, 0};
    {
        const float* p0 = m->positions + 3 * (size_t)out[0];
        const float* p1 = m->positions + 3 * (size_t)out[1];
        const float* p2 = m->positions + 3 * (size_t)out[2];
        const double e1[3] = {(double)p1[0] - p0[0], (double)p1[1] - p0[1], (double)p1[2] - p0[2]};
        const double e2[3] = {(double)p2[0] - p0[0], (double)p2[1] - p0[1], (double)p2[2] - p0[2]};
        fn[0] = e1[1] * e2[2] - e1[2] * e2[1];
        fn[1] = e1[2] * e2[0] - e1[0] * e2[2];
        fn[2] = e1[0] * e2[1] - e1[1] * e2[0];
        const double len = sqrt(fn[0] * fn[0] + fn[1] * fn[1] + fn[2] * fn[2]);
        for (int k = 0; k < 3 && len > 0; ++k)
            fn[k] /= len;
    }
    if ((uint64_t)n[0] * n[1] * n[2] <= 512) { /* every combination */
        double best = INFINITY;
        for (uint32_t i = 0; i < n[0]; ++i)
            for (uint32_t j = 0; j < n[1]; ++j)
                for (uint32_t k = 0; k < n[2]; ++k) {
                    const uint32_t c[3] = {cp[0][i], cp[1][j], cp[2][k]};
                    const double cost = corner_cost(m, c, fn);
                    if (cost < best) {
                        best = cost;
                        memcpy(out, c, sizeof(c));
                    }
                }
        return;
    }
    /* A position with very many copies: one corner at a time against the
     * others' current choice. */
    for (int k = 0; k < 3; ++k) {
        double best = INFINITY;
        uint32_t c[3] = {out[0], out[1], out[2]};
        for (uint32_t i = 0; i < n[k]; ++i) {
            c[k] = cp[k][i];
            const double cost = corner_cost(m, c, fn);
            if (cost < best) {
                best = cost;
                out[k] = c[k];
            }
        }
    }
}

/* The level mesh from `nt` triangles of original-vertex corners `corners`:
 * the vertices they use, in their original order, with their attributes. */
static int make_level_mesh(const meso_mesh* m, const uint32_t* corners, uint32_t nt, uint32_t* scratch,
                           meso_mesh* out)
{
    memset(out, 0, sizeof(*out));
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        scratch[v] = UINT32_MAX;
    for (size_t c = 0; c < 3 * (size_t)nt; ++c)
        scratch[corners[c]] = 0;
    uint32_t nv = 0;
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        if (scratch[v] != UINT32_MAX)
            scratch[v] = nv++;
    out->vertex_count = nv;
    out->triangle_count = nt;
    out->positions = malloc(sizeof(float) * 3 * (nv ? nv : 1));
    out->indices = malloc(sizeof(uint32_t) * 3 * (nt ? nt : 1));
    out->normals = m->normals ? malloc(sizeof(float) * 3 * (nv ? nv : 1)) : NULL;
    out->uvs = m->uvs ? malloc(sizeof(float) * 2 * (nv ? nv : 1)) : NULL;
    if (!out->positions || !out->indices || (m->normals && !out->normals) || (m->uvs && !out->uvs)) {
        meso_mesh_free(out);
        return 0;
    }
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        const uint32_t d = scratch[v];
        if (d == UINT32_MAX)
            continue;
        memcpy(out->positions + 3 * (size_t)d, m->positions + 3 * (size_t)v, 3 * sizeof(float));
        if (m->normals)
            memcpy(out->normals + 3 * (size_t)d, m->normals + 3 * (size_t)v, 3 * sizeof(float));
        if (m->uvs)
            memcpy(out->uvs + 2 * (size_t)d, m->uvs + 2 * (size_t)v, 2 * sizeof(float));
    }
    for (size_t c = 0; c < 3 * (size_t)nt; ++c)
        out->indices[c] = scratch[corners[c]];
    return 1;
}

meso_result meso_mesh_subset(const meso_mesh* m, const uint32_t* corners, uint32_t nt, meso_mesh* out)
{
    uint32_t* scratch = malloc(sizeof(uint32_t) * (m->vertex_count ? m->vertex_count : 1));
    const int ok = scratch && make_level_mesh(m, corners, nt, scratch, out);
    free(scratch);
    return ok ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
}

/* Welded positions: *wpos (3 floats per welded vertex), *windex (the mesh's
 * indices in welded ids), the copies of each; or, with split_seams, the
 * mesh as given (every vertex its own copy). */
static meso_result weld(const meso_mesh* m, int split_seams, float** wpos, uint32_t* wcount, uint32_t** windex,
                        weld_map* wm)
{
    const size_t nv = m->vertex_count, ni = 3 * (size_t)m->triangle_count;
    uint32_t* remap = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    *windex = malloc(sizeof(uint32_t) * (ni ? ni : 1));
    if (!remap || !*windex) {
        free(remap);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    size_t n;
    if (split_seams) {
        for (size_t v = 0; v < nv; ++v)
            remap[v] = (uint32_t)v;
        n = nv;
    } else {
        n = meshopt_generateVertexRemap(remap, m->indices, ni, m->positions, nv, 3 * sizeof(float));
    }
    *wcount = (uint32_t)n;
    *wpos = malloc(sizeof(float) * 3 * (n ? n : 1));
    wm->start = calloc(n + 2, sizeof(uint32_t));
    wm->copies = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    if (!*wpos || !wm->start || !wm->copies) {
        free(remap);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < ni; ++i)
        (*windex)[i] = remap[m->indices[i]];
    if (split_seams) /* unused vertices too: the simplifier reads them all */
        memcpy(*wpos, m->positions, sizeof(float) * 3 * nv);
    /* Copies: the vertices some triangle uses, grouped by welded id. */
    uint8_t* used = calloc(nv ? nv : 1, 1);
    if (!used) {
        free(remap);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < ni; ++i)
        used[m->indices[i]] = 1;
    for (size_t v = 0; v < nv; ++v)
        if (used[v])
            wm->start[remap[v] + 2]++;
    for (size_t w = 0; w < n; ++w)
        wm->start[w + 2] += wm->start[w + 1];
    for (size_t v = 0; v < nv; ++v)
        if (used[v]) {
            wm->copies[wm->start[remap[v] + 1]++] = (uint32_t)v;
            memcpy(*wpos + 3 * (size_t)remap[v], m->positions + 3 * v, 3 * sizeof(float));
        }
    free(used);
    free(remap);
    return MESO_OK;
}

/* A face's vertices in ascending order (either winding), and the face. */
typedef struct face_key {
    uint32_t v[3];
    uint32_t face;
} face_key;

static int by_face_key(const void* a, const void* b)
{
    const face_key* x = a;
    const face_key* y = b;
    for (int k = 0; k < 3; ++k)
        if (x->v[k] != y->v[k])
            return x->v[k] < y->v[k] ? -1 : 1;
    return x->face < y->face ? -1 : x->face > y->face ? 1 : 0;
}

/* meshopt_simplify (0.18) now and then leaves two faces on the same three
 * vertices (measured on the armadillo: one such pair in 5 of its 7
 * levels), of one winding or of both (a doubled sheet). The first of them
 * stays, the others go: dropping both of a reversed pair instead removes
 * what the sheet covers (the armadillo's level 7 error doubled, spot's
 * level 5 too). Returns the new index count; kept faces keep their order. */
static size_t drop_duplicate_faces(uint32_t* idx, size_t n, face_key* keys, uint8_t* keep)
{
    const size_t nt = n / 3;
    for (size_t t = 0; t < nt; ++t) {
        uint32_t a = idx[3 * t], b = idx[3 * t + 1], c = idx[3 * t + 2], x;
        if (a > b)
            x = a, a = b, b = x;
        if (b > c)
            x = b, b = c, c = x;
        if (a > b)
            x = a, a = b, b = x;
        keys[t] = (face_key){{a, b, c}, (uint32_t)t};
        keep[t] = 1;
    }
    qsort(keys, nt, sizeof(*keys), by_face_key); /* ties by face: the first comes first */
    for (size_t i = 1; i < nt; ++i)
        if (!memcmp(keys[i].v, keys[i - 1].v, sizeof(keys[i].v)))
            keep[keys[i].face] = 0;
    size_t out = 0;
    for (size_t t = 0; t < nt; ++t)
        if (keep[t]) {
            memmove(idx + out, idx + 3 * t, 3 * sizeof(uint32_t));
            out += 3;
        }
    return out;
}

size_t mesoi_drop_duplicate_faces(uint32_t* idx, size_t n)
{
    face_key* keys = malloc(sizeof(face_key) * (n / 3 ? n / 3 : 1));
    uint8_t* keep = malloc(n / 3 ? n / 3 : 1);
    const size_t out = keys && keep ? drop_duplicate_faces(idx, n, keys, keep) : SIZE_MAX;
    free(keys);
    free(keep);
    return out;
}

static meso_result build_chain(const meso_mesh* m, const meso_mesh_levels_options* o, int max_levels,
                               meso_mesh_level** levels, uint32_t* count, meso_error* err)
{
    float* wpos = NULL;
    uint32_t wcount = 0, *windex = NULL, *cur = NULL, *next = NULL, *corners = NULL, *scratch = NULL;
    weld_map wm = {NULL, NULL};
    face_key* keys = NULL;
    uint8_t* keep = NULL;
    meso_mesh_level* out = calloc((size_t)max_levels, sizeof(*out));
    uint32_t made = 0;
    meso_surface_ref ref; /* level 0, measured against every level */
    int have_ref = 0;
    const size_t ni = 3 * (size_t)m->triangle_count;
    meso_result r = out ? weld(m, o->split_seams, &wpos, &wcount, &windex, &wm) : MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_OK) {
        cur = malloc(sizeof(uint32_t) * (ni ? ni : 1));
        next = malloc(sizeof(uint32_t) * (ni ? ni : 1));
        corners = malloc(sizeof(uint32_t) * (ni ? ni : 1));
        scratch = malloc(sizeof(uint32_t) * (m->vertex_count ? m->vertex_count : 1));
        keys = malloc(sizeof(face_key) * (m->triangle_count ? m->triangle_count : 1));
        keep = malloc(m->triangle_count ? m->triangle_count : 1);
        r = cur && next && corners && scratch && keys && keep ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    if (r != MESO_OK) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "mesh levels: out of memory");
        goto done;
    }
    memcpy(cur, windex, sizeof(uint32_t) * ni);
    size_t cur_n = ni;
    const double spacing = o->spacing > 0 ? o->spacing : 0.5 * meso_mesh_mean_edge(m);
    double running = 0;
    const uint32_t min_tris = o->min_triangles ? o->min_triangles : MESO_MESH_LEVELS_MIN_TRIANGLES;
    const unsigned options = o->lock_border ? meshopt_SimplifyLockBorder : 0;
    while ((int)made + 1 < max_levels && cur_n / 3 > min_tris) {
        const size_t target = (cur_n / 3 / 2) * 3;
        size_t got = meshopt_simplify(next, cur, cur_n, wpos, wcount, 3 * sizeof(float), target, 1.0f, options, NULL);
        got = drop_duplicate_faces(next, got, keys, keep);
        if (got == 0 || (double)got > 0.85 * (double)cur_n)
            break; /* terminal */
        for (size_t t = 0; t < got / 3; ++t)
            pick_copies(m, &wm, next + 3 * t, corners + 3 * t);
        meso_mesh_level* L = &out[made];
        if (!make_level_mesh(m, corners, (uint32_t)(got / 3), scratch, &L->mesh)) {
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "mesh levels: out of memory");
            goto done;
        }
        ++made;
        if (!have_ref && (r = meso_surface_ref_build(m, &ref, err)) != MESO_OK)
            goto done;
        have_ref = 1;
        r = meso_surface_distance_to_ref(&L->mesh, &ref, spacing, o->threads, &L->measured, &L->sample_radius, err);
        if (r != MESO_OK)
            goto done;
        running = L->measured > running ? L->measured : running;
        L->error = running;
        meso_mesh_bounds(&L->mesh, L->bbox_min, L->bbox_max);
        memcpy(cur, next, sizeof(uint32_t) * got);
        cur_n = got;
    }
done:
    if (have_ref)
        meso_surface_ref_free(&ref);
    free(wpos);
    free(windex);
    free(wm.start);
    free(wm.copies);
    free(cur);
    free(next);
    free(corners);
    free(scratch);
    free(keys);
    free(keep);
    if (r != MESO_OK) {
        meso_mesh_levels_free(out, made);
        return r;
    }
    *levels = out;
    *count = made;
    return MESO_OK;
}
#endif /* MESO_HAVE_MESHOPTIMIZER */

meso_result meso_mesh_levels_build(const meso_mesh* m, const meso_mesh_levels_options* o, meso_mesh_level** levels,
                                   uint32_t* count, meso_error* err)
{
    *levels = NULL;
    *count = 0;
    const meso_mesh_levels_options defaults = {0};
    if (!o)
        o = &defaults;
    const int max_levels = o->max_levels <= 0 ? MESO_MESH_LEVELS_MAX : o->max_levels;
    if (max_levels > 65535)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "mesh levels: %d levels asked for, at most 65535",
                              max_levels);
    if (max_levels == 1 || !m || m->triangle_count == 0)
        return MESO_OK;
#if MESO_HAVE_MESHOPTIMIZER
    return build_chain(m, o, max_levels, levels, count, err);
#else
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                          "mesh levels of detail need meshoptimizer: this build has none (-Dmeshoptimizer)");
#endif
}
