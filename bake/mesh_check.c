/*
 * mesh_check.c — edge classification of an indexed triangle mesh.
 *
 * Every face contributes its three directed edges; sorting them by their
 * undirected key groups each edge's uses together, so one pass classifies
 * it: one use is a boundary, two uses in opposite directions a manifold
 * interior edge, two in the same direction a misoriented one, more than two
 * non-manifold. Sorting (not hashing) keeps the result and the order of the
 * boundary list independent of memory layout and thread count.
 */
#include "mesh_check.h"

#include <stdlib.h>
#include <string.h>

typedef struct dedge {
    uint64_t key;  /* min << 32 | max */
    uint32_t from; /* the face traverses from -> to */
    uint32_t face;
} dedge;

static int cmp_dedge(const void* a, const void* b)
{
    const dedge *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->face < y->face ? -1 : x->face > y->face;
}

typedef struct face_key {
    uint32_t v[3]; /* sorted */
    uint32_t face;
} face_key;

static int cmp_face_key(const void* a, const void* b)
{
    const face_key *x = a, *y = b;
    for (int k = 0; k < 3; ++k)
        if (x->v[k] != y->v[k])
            return x->v[k] < y->v[k] ? -1 : 1;
    return x->face < y->face ? -1 : x->face > y->face;
}

static void note_bad(meso_mesh_topology* t, uint32_t face)
{
    if (face < t->first_bad_face)
        t->first_bad_face = face;
}

meso_result meso_mesh_topology_compute(const meso_mesh* m, double area_eps, meso_mesh_topology* t, meso_error* err)
{
    memset(t, 0, sizeof(*t));
    t->first_bad_face = UINT32_MAX;
    const size_t nf = m->triangle_count, ne = 3 * nf;
    dedge* e = malloc(sizeof(dedge) * (ne ? ne : 1));
    face_key* fk = malloc(sizeof(face_key) * (nf ? nf : 1));
    uint8_t* used = calloc(m->vertex_count ? m->vertex_count : 1, 1);
    if (!e || !fk || !used) {
        free(e);
        free(fk);
        free(used);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "mesh check: out of memory");
    }
    size_t ne_used = 0;
    for (size_t f = 0; f < nf; ++f) {
        const uint32_t* ix = m->indices + 3 * f;
        double n[3];
        for (int k = 0; k < 3; ++k) {
            const uint32_t a = ix[k], b = ix[(k + 1) % 3];
            used[a] = 1;
            if (a == b)
                continue; /* a repeated index: the face is degenerate, not an edge */
            e[ne_used++] = (dedge){.key = a < b ? ((uint64_t)a << 32 | b) : ((uint64_t)b << 32 | a),
                                           .from = a,
                                           .face = (uint32_t)f};
        }
        if (ix[0] == ix[1] || ix[1] == ix[2] || ix[0] == ix[2] || 0.5 * meso_mesh_face_normal(m, (uint32_t)f, n) <= area_eps) {
            t->degenerate_faces++;
            note_bad(t, (uint32_t)f);
        }
        face_key* k = &fk[f];
        uint32_t a = ix[0], b = ix[1], c = ix[2], s;
        if (a > b) s = a, a = b, b = s;
        if (b > c) s = b, b = c, c = s;
        if (a > b) s = a, a = b, b = s;
        *k = (face_key){{a, b, c}, (uint32_t)f};
    }
    qsort(fk, nf, sizeof(face_key), cmp_face_key);
    for (size_t f = 1; f < nf; ++f)
        if (!memcmp(fk[f].v, fk[f - 1].v, sizeof(fk[f].v))) {
            t->duplicate_faces++;
            note_bad(t, fk[f].face);
        }
    free(fk);
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        t->unused_vertices += !used[v];
    free(used);

    qsort(e, ne_used, sizeof(dedge), cmp_dedge);
    size_t nb = 0;
    for (size_t i = 0; i < ne_used;) {
        size_t j = i + 1;
        while (j < ne_used && e[j].key == e[i].key)
            ++j;
        const size_t uses = j - i;
        t->edges++;
        if (uses == 1) {
            t->boundary_edges++;
        } else if (uses == 2) {
            if (e[i].from == e[i + 1].from) {
                t->misoriented_edges++;
                note_bad(t, e[i + 1].face);
            }
        } else {
            t->nonmanifold_edges++;
            note_bad(t, e[i].face);
        }
        i = j;
    }
    if (t->boundary_edges) {
        t->boundary = malloc(sizeof(uint32_t) * 2 * t->boundary_edges);
        if (!t->boundary) {
            free(e);
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "mesh check: out of memory");
        }
        for (size_t i = 0; i < ne_used;) {
            size_t j = i + 1;
            while (j < ne_used && e[j].key == e[i].key)
                ++j;
            if (j - i == 1) {
                const uint32_t a = e[i].from, lo = (uint32_t)(e[i].key >> 32), hi = (uint32_t)e[i].key;
                t->boundary[2 * nb] = a;
                t->boundary[2 * nb + 1] = a == lo ? hi : lo;
                ++nb;
            }
            i = j;
        }
    }
    free(e);
    return MESO_OK;
}

meso_result meso_mesh_topology_require_shellable(const meso_mesh_topology* t, const char* what, meso_error* err)
{
    if (t->nonmanifold_edges)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 3110,
                              "%s: %u non-manifold edges (more than two faces share an edge, e.g. at face %u); "
                              "a shell needs a manifold surface",
                              what, t->nonmanifold_edges, t->first_bad_face);
    if (t->misoriented_edges)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 3111,
                              "%s: inconsistent orientation at %u edges (e.g. face %u): neighbouring faces "
                              "disagree on inside and outside",
                              what, t->misoriented_edges, t->first_bad_face);
    if (t->duplicate_faces)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 3112, "%s: %u duplicated faces (e.g. face %u)", what,
                              t->duplicate_faces, t->first_bad_face);
    if (t->degenerate_faces)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, 3113,
                              "%s: %u degenerate faces (repeated vertex or zero area, e.g. face %u)", what,
                              t->degenerate_faces, t->first_bad_face);
    return MESO_OK;
}
