/*
 * skeleton_mesh_checks.c — stage 1 of meso_skeleton_from_mesh: refuse what
 * CGAL's mean-curvature flow cannot take, and make the compact copy it gets.
 *
 * skeleton_from_mesh.h, 1.: CGAL's flow crashes rather than fails on open or
 * multi-component input, so before it the mesh must be closed (every edge
 * in exactly two faces), consistently oriented, edge- and vertex-manifold (a
 * vertex's faces form one fan), one connected component, without zero-area
 * (area <= 1e-12 diag^2) or duplicated faces, and enclose a non-zero volume.
 * Vertices no face uses are dropped, not refused; an inside-out mesh is
 * flipped for CGAL, whose Voronoi poles are picked against the vertex
 * normals. The issue codes 3170..3176 are listed there.
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_check.h"
#include "skeleton_from_mesh_internal.h"

void mesoi_clean_mesh_free(mesoi_clean_mesh* c)
{
    free(c->xyz);
    free(c->tri);
    free(c->orig);
    memset(c, 0, sizeof(*c));
}

static uint32_t uf_find(uint32_t* up, uint32_t x)
{
    while (up[x] != x) {
        up[x] = up[up[x]];
        x = up[x];
    }
    return x;
}

typedef struct half_edge {
    uint64_t key; /* from << 32 | to */
    uint32_t face, corner;
} half_edge;

static int cmp_half_edge(const void* a, const void* b)
{
    const half_edge *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key;
}

static const half_edge* find_half_edge(const half_edge* h, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        const size_t mid = lo + (hi - lo) / 2;
        if (h[mid].key < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && h[lo].key == key ? &h[lo] : NULL;
}

/* Vertices whose faces form more than one fan. Needs a closed, edge-manifold,
 * consistently oriented mesh: every half-edge then has exactly one twin, and
 * turning around v (v->w in face f, then the twin of f's edge u->v, which is
 * v->u in the next face) visits one fan; its length must be v's face count. */
static meso_result count_fan_defects(const uint32_t* tri, uint32_t nt, uint32_t nv, uint32_t* defects,
                                     uint32_t* first, meso_error* err)
{
    const size_t nh = 3 * (size_t)nt;
    half_edge* h = malloc(sizeof(half_edge) * (nh ? nh : 1));
    uint32_t* corners = calloc(nv ? nv : 1, sizeof(uint32_t));
    uint8_t* seen = calloc(nv ? nv : 1, 1);
    if (!h || !corners || !seen) {
        free(h);
        free(corners);
        free(seen);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    for (uint32_t f = 0; f < nt; ++f)
        for (uint32_t k = 0; k < 3; ++k) {
            const uint32_t a = tri[3 * f + k], b = tri[3 * f + (k + 1) % 3];
            h[3 * (size_t)f + k] = (half_edge){(uint64_t)a << 32 | b, f, k};
            corners[a]++;
        }
    qsort(h, nh, sizeof(half_edge), cmp_half_edge);
    *defects = 0;
    *first = UINT32_MAX;
    for (size_t i = 0; i < nh; ++i) {
        const uint32_t v = (uint32_t)(h[i].key >> 32);
        if (seen[v])
            continue;
        seen[v] = 1;
        uint32_t len = 0;
        const half_edge* e = &h[i];
        do {
            const uint32_t u = tri[3 * e->face + (e->corner + 2) % 3]; /* u -> v precedes v -> w in the face */
            e = find_half_edge(h, nh, (uint64_t)v << 32 | u);
            ++len;
        } while (e && e != &h[i] && len <= corners[v]);
        if (!e || len != corners[v]) {
            if (*defects == 0)
                *first = v;
            ++*defects;
        }
    }
    free(h);
    free(corners);
    free(seen);
    return MESO_OK;
}

static meso_result check_topology(const meso_mesh* m, double diag, meso_error* err)
{
    meso_mesh_topology t;
    meso_result r = meso_mesh_topology_compute(m, 1e-12 * diag * diag, &t, err);
    if (r != MESO_OK)
        return r;
    if (t.nonmanifold_edges)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_NONMANIFOLD,
                           "skeleton from mesh: %u non-manifold edges (more than two faces share an edge, e.g. at "
                           "face %u); mean-curvature-flow skeletons need a manifold surface",
                           t.nonmanifold_edges, t.first_bad_face);
    else if (t.boundary_edges)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_OPEN,
                           "skeleton from mesh: the mesh is open: %u boundary edges, the first from vertex %u to "
                           "vertex %u (0-based); a skeleton needs a closed surface (fill the holes, or weld "
                           "duplicated vertices)",
                           t.boundary_edges, t.boundary[0], t.boundary[1]);
    else if (t.misoriented_edges)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_ORIENTATION,
                           "skeleton from mesh: inconsistent orientation at %u edges (e.g. face %u): neighbouring "
                           "faces disagree on inside and outside",
                           t.misoriented_edges, t.first_bad_face);
    else if (t.degenerate_faces || t.duplicate_faces)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_DEGENERATE,
                           "skeleton from mesh: %u degenerate (repeated vertex or zero area) and %u duplicated "
                           "faces, e.g. face %u",
                           t.degenerate_faces, t.duplicate_faces, t.first_bad_face);
    free(t.boundary);
    return r;
}

/* Connected components over the used vertices (union-find along edges;
 * a component's root is its lowest vertex, so they come in that order). */
static meso_result check_components(const mesoi_clean_mesh* c, meso_error* err)
{
    uint32_t* up = malloc(sizeof(uint32_t) * (c->nv ? c->nv : 1));
    uint32_t* size = calloc(c->nv ? c->nv : 1, sizeof(uint32_t));
    if (!up || !size) {
        free(up);
        free(size);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    for (uint32_t v = 0; v < c->nv; ++v)
        up[v] = v;
    for (uint32_t f = 0; f < c->nt; ++f)
        for (int k = 0; k < 2; ++k) {
            const uint32_t a = uf_find(up, c->tri[3 * f + k]), b = uf_find(up, c->tri[3 * f + k + 1]);
            if (a != b)
                up[a > b ? a : b] = a < b ? a : b;
        }
    uint32_t comps = 0, first[2] = {0, 0};
    for (uint32_t v = 0; v < c->nv; ++v)
        size[uf_find(up, v)]++;
    for (uint32_t v = 0; v < c->nv; ++v)
        if (up[v] == v) {
            if (comps < 2)
                first[comps] = v;
            ++comps;
        }
    meso_result r = MESO_OK;
    if (comps > 1)
        r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_COMPONENTS,
                           "skeleton from mesh: %u connected components (the first two have %u and %u vertices, "
                           "from vertex %u and %u); skeletonize each part on its own",
                           comps, size[first[0]], size[first[1]], c->orig[first[0]], c->orig[first[1]]);
    free(up);
    free(size);
    return r;
}

/* Everything the header promises about the input, then the compact copy. */
meso_result mesoi_skel_check_and_clean(const meso_mesh* m, mesoi_clean_mesh* c, meso_error* err)
{
    memset(c, 0, sizeof(*c));
    if (!m->vertex_count || !m->triangle_count || !m->positions || !m->indices)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_SKELFIT_ISSUE_EMPTY,
                              "skeleton from mesh: the mesh has %u vertices and %u triangles", m->vertex_count,
                              m->triangle_count);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; ++i)
        if (m->indices[i] >= m->vertex_count)
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_INDEX,
                                  "skeleton from mesh: triangle %zu refers to vertex %u of %u", i / 3, m->indices[i],
                                  m->vertex_count);
    uint32_t* map = malloc(sizeof(uint32_t) * m->vertex_count);
    if (!map)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        map[v] = UINT32_MAX;
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; ++i)
        map[m->indices[i]] = 0;
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        if (map[v] == 0)
            map[v] = c->nv++;
    c->nt = m->triangle_count;
    c->xyz = malloc(sizeof(double) * 3 * c->nv);
    c->tri = malloc(sizeof(uint32_t) * 3 * (size_t)c->nt);
    c->orig = malloc(sizeof(uint32_t) * c->nv);
    if (!c->xyz || !c->tri || !c->orig) {
        free(map);
        mesoi_clean_mesh_free(c);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    meso_result r = MESO_OK;
    for (uint32_t v = 0; v < m->vertex_count && r == MESO_OK; ++v) {
        if (map[v] == UINT32_MAX)
            continue;
        c->orig[map[v]] = v;
        for (int k = 0; k < 3; ++k) {
            const double x = m->positions[3 * (size_t)v + k];
            if (!isfinite(x)) {
                r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_INDEX,
                                   "skeleton from mesh: vertex %u has a non-finite coordinate", v);
                break;
            }
            c->xyz[3 * (size_t)map[v] + k] = x;
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    }
    for (size_t i = 0; i < 3 * (size_t)c->nt; ++i)
        c->tri[i] = map[m->indices[i]];
    free(map);
    if (r == MESO_OK) {
        c->diag = dist3(hi, lo);
        r = check_topology(m, c->diag, err);
    }
    if (r == MESO_OK) {
        uint32_t defects = 0, first = 0;
        r = count_fan_defects(c->tri, c->nt, c->nv, &defects, &first, err);
        if (r == MESO_OK && defects)
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_NONMANIFOLD,
                               "skeleton from mesh: %u non-manifold vertices (their faces form several fans, e.g. "
                               "vertex %u): the surface touches itself there",
                               defects, c->orig[first]);
    }
    if (r == MESO_OK)
        r = check_components(c, err);
    if (r == MESO_OK) {
        /* Signed volume about the box centre (less cancellation). */
        const double o[3] = {0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1]), 0.5 * (lo[2] + hi[2])};
        double vol = 0;
        for (uint32_t f = 0; f < c->nt; ++f) {
            double p[3][3];
            for (int k = 0; k < 3; ++k)
                sub3(c->xyz + 3 * (size_t)c->tri[3 * f + k], o, p[k]);
            vol += (p[0][0] * (p[1][1] * p[2][2] - p[1][2] * p[2][1]) - p[0][1] * (p[1][0] * p[2][2] - p[1][2] * p[2][0]) +
                    p[0][2] * (p[1][0] * p[2][1] - p[1][1] * p[2][0])) /
                   6.0;
        }
        if (!(fabs(vol) > 1e-12 * c->diag * c->diag * c->diag))
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_DEGENERATE,
                               "skeleton from mesh: the closed surface encloses no volume (%g)", vol);
        else if (vol < 0) {
            c->flipped = 1;
            for (uint32_t f = 0; f < c->nt; ++f) {
                const uint32_t s = c->tri[3 * f + 1];
                c->tri[3 * f + 1] = c->tri[3 * f + 2];
                c->tri[3 * f + 2] = s;
            }
        }
    }
    if (r != MESO_OK)
        mesoi_clean_mesh_free(c);
    return r;
}
