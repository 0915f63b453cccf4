/*
 * mesh_weld.c — welding a triangle soup by position (mesh_weld.h): a hash
 * of the positions' bits, open addressing, linear probing; then the corner
 * uvs and OpenMesh-style vertex normals of the welded mesh.
 */
#include "mesh_weld.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static uint64_t position_key(const float* p, uint32_t bits[3])
{
    uint64_t h = 1469598103934665603ull;
    for (int k = 0; k < 3; ++k) {
        const float f = p[k] == 0.0f ? 0.0f : p[k]; /* -0 welds with +0 */
        memcpy(&bits[k], &f, 4);
        h = (h ^ bits[k]) * 1099511628211ull;
        h ^= h >> 29;
    }
    return h;
}

/* remap[v] = welded index of soup vertex v; *welded = their count. */
static int weld_positions(const meso_weld_input* in, uint32_t* remap, uint32_t* first, uint32_t* welded)
{
    size_t cap = 16;
    while (cap < 2 * in->vertex_count)
        cap *= 2;
    uint32_t* table = malloc(cap * sizeof(uint32_t)); /* soup vertex + 1, 0 = empty */
    if (!table)
        return 0;
    memset(table, 0, cap * sizeof(uint32_t));
    uint32_t n = 0;
    for (size_t v = 0; v < in->vertex_count; ++v) {
        uint32_t bits[3], other[3];
        size_t slot = (size_t)position_key(in->positions + 3 * v, bits) & (cap - 1);
        for (;; slot = (slot + 1) & (cap - 1)) {
            if (table[slot] == 0) {
                table[slot] = (uint32_t)v + 1;
                first[n] = (uint32_t)v;
                remap[v] = n++;
                break;
            }
            const uint32_t u = table[slot] - 1;
            position_key(in->positions + 3 * (size_t)u, other);
            if (memcmp(bits, other, sizeof(bits)) == 0) {
                remap[v] = remap[u];
                break;
            }
        }
    }
    free(table);
    *welded = n;
    return 1;
}

/* Vertices no kept triangle uses are dropped, the others keep their order
 * (`scratch`: vertex_count entries). */
static void drop_unused(meso_mesh* m, uint32_t* scratch)
{
    const uint32_t none = UINT32_MAX;
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        scratch[v] = none;
    for (size_t c = 0; c < 3 * (size_t)m->triangle_count; ++c)
        scratch[m->indices[c]] = 0;
    uint32_t n = 0;
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        if (scratch[v] != none) {
            memmove(m->positions + 3 * (size_t)n, m->positions + 3 * (size_t)v, 3 * sizeof(float));
            scratch[v] = n++;
        }
    for (size_t c = 0; c < 3 * (size_t)m->triangle_count; ++c)
        m->indices[c] = scratch[m->indices[c]];
    m->vertex_count = n;
}

/* Corner uvs as the OpenMesh reader keeps OBJ's: the vertex uv is its last
 * corner's; corner_uvs only when some corner differs from it (a seam). */
static int weld_uvs(const meso_weld_input* in, const uint32_t* soup_corner, meso_mesh* m)
{
    const size_t nt = m->triangle_count;
    m->uvs = calloc(m->vertex_count ? 2 * (size_t)m->vertex_count : 1, sizeof(float));
    float* cuv = malloc(sizeof(float) * 6 * (nt ? nt : 1));
    if (!m->uvs || !cuv) {
        free(cuv);
        return 0;
    }
    for (size_t c = 0; c < 3 * nt; ++c) {
        memcpy(cuv + 2 * c, in->uvs + 2 * (size_t)soup_corner[c], 2 * sizeof(float));
        memcpy(m->uvs + 2 * (size_t)m->indices[c], cuv + 2 * c, 2 * sizeof(float));
    }
    int seam = 0;
    for (size_t c = 0; c < 3 * nt && !seam; ++c)
        seam = memcmp(cuv + 2 * c, m->uvs + 2 * (size_t)m->indices[c], 2 * sizeof(float)) != 0;
    if (seam)
        m->corner_uvs = cuv;
    else
        free(cuv);
    return 1;
}

/* Normalised sum of the unit face normals around each vertex (OpenMesh's
 * update_normals); (0, 0, 0) for a vertex on degenerate faces only. */
static void vertex_normals(meso_mesh* m)
{
    double* acc = calloc(3 * (size_t)(m->vertex_count ? m->vertex_count : 1), sizeof(double));
    if (!acc)
        return;
    for (uint32_t f = 0; f < m->triangle_count; ++f) {
        double n[3];
        meso_mesh_face_normal(m, f, n);
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j)
                acc[3 * (size_t)m->indices[3 * (size_t)f + (size_t)k] + (size_t)j] += n[j];
    }
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        const double* a = acc + 3 * (size_t)v;
        const double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        for (int j = 0; j < 3; ++j)
            m->normals[3 * (size_t)v + (size_t)j] = len > 0.0 ? (float)(a[j] / len) : 0.0f;
    }
    free(acc);
}

meso_result meso_mesh_weld(const meso_weld_input* in, meso_mesh* out, uint32_t** tags, uint32_t* dropped,
                           meso_error* err)
{
    memset(out, 0, sizeof(*out));
    if (tags)
        *tags = NULL;
    *dropped = 0;
    const size_t nv = in->vertex_count, nt = in->triangle_count;
    if (nv > UINT32_MAX / 4 || nt > UINT32_MAX / 8)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "weld: %zu vertices, %zu triangles: too many", nv, nt);
    uint32_t* remap = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    uint32_t* first = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    uint32_t* soup_corner = malloc(sizeof(uint32_t) * 3 * (nt ? nt : 1));
    uint32_t* kept_tags = in->triangle_tags && tags ? malloc(sizeof(uint32_t) * (nt ? nt : 1)) : NULL;
    out->indices = malloc(sizeof(uint32_t) * 3 * (nt ? nt : 1));
    uint32_t welded = 0;
    int ok = remap && first && soup_corner && out->indices && (kept_tags || !(in->triangle_tags && tags)) &&
             weld_positions(in, remap, first, &welded);
    if (ok) {
        out->vertex_count = welded;
        out->positions = malloc(sizeof(float) * 3 * (welded ? welded : 1));
        out->normals = calloc(3 * (size_t)(welded ? welded : 1), sizeof(float));
        ok = out->positions && out->normals;
    }
    if (ok) {
        for (uint32_t v = 0; v < welded; ++v)
            memcpy(out->positions + 3 * (size_t)v, in->positions + 3 * (size_t)first[v], 3 * sizeof(float));
        uint32_t t_out = 0;
        for (size_t t = 0; t < nt; ++t) {
            const uint32_t* s = in->indices + 3 * t;
            const uint32_t a = remap[s[0]], b = remap[s[1]], c = remap[s[2]];
            if (a == b || b == c || a == c) {
                ++*dropped;
                continue;
            }
            uint32_t* d = out->indices + 3 * (size_t)t_out;
            d[0] = a, d[1] = b, d[2] = c;
            memcpy(soup_corner + 3 * (size_t)t_out, s, 3 * sizeof(uint32_t));
            if (kept_tags)
                kept_tags[t_out] = in->triangle_tags[t];
            ++t_out;
        }
        out->triangle_count = t_out;
        drop_unused(out, first);
        ok = !in->uvs || weld_uvs(in, soup_corner, out);
    }
    if (ok)
        vertex_normals(out);
    free(remap);
    free(first);
    free(soup_corner);
    if (!ok) {
        free(kept_tags);
        meso_mesh_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "weld: out of memory");
    }
    if (tags)
        *tags = kept_tags;
    return MESO_OK;
}
