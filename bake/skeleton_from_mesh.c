/*
 * skeleton_from_mesh.c — closed mesh -> skeleton with radii, simplified to a
 * tolerance. The decisions are in skeleton_from_mesh.h; this file says how.
 *
 * Stages (greppable banners): >>geometry (the public distances), >>checks,
 * >>tree (CGAL's graph to a spanning tree), >>radii, >>model (the union of
 * round-ended frusta), >>mesh-distance (exact point-to-mesh distance for
 * the model -> mesh direction), >>fit (split, least squares, merge),
 * >>output, >>main.
 */
#include "skeleton_from_mesh.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "mesh_check.h"
#include "meso_clock.h"
#include "vec3d.h" /* dot3, cross3, normalize3, any_perp3 (runtime/, shared with the references) */
#if MESO_HAVE_CGAL
#include "adapters.h"
#endif

/* The least-squares prior's weight, relative to a node's data curvature. */
#define MESO_SKELFIT_PRIOR 1e-2
/* Conjugate-gradient steps per Levenberg–Marquardt step (an inexact step
 * is enough: the outer iteration corrects it). */
#define MESO_SKELFIT_CG_ITERATIONS 100
/* Levenberg–Marquardt steps per refit (it stops earlier once the cost
 * changes by less than 1e-6 relative). */
#define MESO_SKELFIT_LM_ITERATIONS 30

/* >>geometry ------------------------------------------------------------ */
/* Distance in the plane from (x, y) to the segment (x0, y0)-(x1, y1). */
static double dist_seg2(double x, double y, double x0, double y0, double x1, double y1)
{
    const double dx = x1 - x0, dy = y1 - y0, l2 = dx * dx + dy * dy;
    double t = l2 > 0 ? ((x - x0) * dx + (y - y0) * dy) / l2 : 0;
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return hypot(x - x0 - t * dx, y - y0 - t * dy);
}

/* Axial coordinate y (from a, along a -> b) and radial distance rho of p;
 * returns the axis length h (0: y = 0, rho = |p - a|). */
static double axial_radial(const double a[3], const double b[3], const double p[3], double* y, double* rho)
{
    double ax[3], d[3], c[3];
    sub3(b, a, ax);
    sub3(p, a, d);
    const double h = sqrt(dot3(ax, ax));
    if (h <= 0) {
        *y = 0;
        *rho = sqrt(dot3(d, d));
        return 0;
    }
    *y = dot3(d, ax) / h;
    cross3(d, ax, c);
    *rho = sqrt(dot3(c, c)) / h; /* |d x ax| / h: accurate near the axis */
    return h;
}

double meso_cone_frustum_distance(const double a[3], double ra, const double b[3], double rb, const double p[3])
{
    double y, rho;
    const double h = axial_radial(a, b, p, &y, &rho);
    if (h <= 0)
        return rho - (ra > rb ? ra : rb);
    /* The solid is the revolved trapezoid 0 <= y <= h, 0 <= rho <= r(y);
     * its surface is the bottom cap, the side and the top cap (the axis
     * edge rho = 0 is inside the solid, not surface). */
    const double d0 = dist_seg2(y, rho, 0, 0, 0, ra);
    const double d1 = dist_seg2(y, rho, 0, ra, h, rb);
    const double d2 = dist_seg2(y, rho, h, rb, h, 0);
    double d = d0 < d1 ? d0 : d1;
    d = d < d2 ? d : d2;
    const int inside = y >= 0 && y <= h && rho <= ra + (rb - ra) * (y / h);
    return inside ? -d : d;
}

double meso_skeleton_surface_distance(const meso_skeleton* s, const double p[3])
{
    double best = DBL_MAX;
    for (uint32_t i = 0; i < s->node_count; ++i) {
        const meso_skeleton_node* nd = &s->nodes[i];
        double d = dist3(p, nd->pos) - nd->radius;
        if (nd->parent >= 0) {
            const meso_skeleton_node* pa = &s->nodes[nd->parent];
            const double f = meso_cone_frustum_distance(pa->pos, pa->radius, nd->pos, nd->radius, p);
            d = f < d ? f : d;
        }
        best = d < best ? d : best;
    }
    return best;
}

#if MESO_HAVE_CGAL /* the rest serves meso_skeleton_from_mesh, which needs CGAL */

/* Parameter of p's projection on segment a -> b, unclamped (0 if a == b). */
static double seg_param(const double a[3], const double b[3], const double p[3])
{
    double ab[3], ap[3];
    sub3(b, a, ab);
    sub3(p, a, ap);
    const double l2 = dot3(ab, ab);
    return l2 > 0 ? dot3(ap, ab) / l2 : 0;
}

/* Distance from p to the point of a -> b at parameter t. */
static double dist_at(const double a[3], const double b[3], double t, const double p[3])
{
    const double q[3] = {a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1]), a[2] + t * (b[2] - a[2])};
    return dist3(p, q);
}

static double dist_segment(const double a[3], const double b[3], const double p[3])
{
    double t = seg_param(a, b, p);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return dist_at(a, b, t, p);
}

/* >>checks -------------------------------------------------------------- */

/* The mesh as CGAL gets it: used vertices only, outward orientation. */
typedef struct clean_mesh {
    uint32_t nv, nt;
    double* xyz;    /* 3 * nv */
    uint32_t* tri;  /* 3 * nt, compact indices */
    uint32_t* orig; /* compact -> input vertex index */
    double diag;
    int flipped;
} clean_mesh;

static void clean_mesh_free(clean_mesh* c)
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
static meso_result check_components(const clean_mesh* c, meso_error* err)
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
static meso_result check_and_clean(const meso_mesh* m, clean_mesh* c, meso_error* err)
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
        clean_mesh_free(c);
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
        c->diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
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
        clean_mesh_free(c);
    return r;
}

/* >>tree ---------------------------------------------------------------- */

/* The working tree: CGAL's nodes 0 .. ncgal-1, then the copies made by
 * cutting cycles. Mesh vertices belong to CGAL nodes (vstart/vlist over
 * ncgal; copies own none). */
typedef struct work_tree {
    uint32_t ncgal, n;
    double* pos;       /* 3 * n */
    double* rad;       /* n */
    int32_t* parent;   /* n, -1 for a root */
    uint32_t* src;     /* n: the CGAL node a node is (a copy's original) */
    uint32_t* cstart;  /* n + 1: children of i are child[cstart[i] .. cstart[i+1]) */
    uint32_t* child;
    uint32_t* vstart;  /* ncgal + 1 */
    uint32_t* vlist;   /* mesh vertices, grouped by node */
    uint32_t* adj_start; /* ncgal + 1: CGAL graph adjacency (deduplicated) */
    uint32_t* adj;
    uint32_t roots, cycles, unmapped, edges;
} work_tree;

static void work_tree_free(work_tree* w)
{
    free(w->pos);
    free(w->rad);
    free(w->parent);
    free(w->src);
    free(w->cstart);
    free(w->child);
    free(w->vstart);
    free(w->vlist);
    free(w->adj_start);
    free(w->adj);
    memset(w, 0, sizeof(*w));
}

static inline uint32_t tree_degree(const work_tree* w, uint32_t i)
{
    return w->cstart[i + 1] - w->cstart[i] + (w->parent[i] >= 0);
}

static int cmp_u64(const void* a, const void* b)
{
    const uint64_t x = *(const uint64_t*)a, y = *(const uint64_t*)b;
    return x < y ? -1 : x > y;
}

/* CGAL's graph (deduplicated) and its correspondence, inverted to a
 * vertex -> node owner and regrouped. */
static meso_result take_cgal(const clean_mesh* c, const meso_cgal_skeleton* s, work_tree* w, meso_error* err)
{
    const uint32_t n = s->vertex_count;
    w->ncgal = n;
    uint64_t* e = malloc(sizeof(uint64_t) * (s->edge_count ? s->edge_count : 1));
    uint32_t* owner = malloc(sizeof(uint32_t) * (c->nv ? c->nv : 1));
    w->adj_start = calloc((size_t)n + 1, sizeof(uint32_t));
    w->vstart = calloc((size_t)n + 1, sizeof(uint32_t));
    w->vlist = malloc(sizeof(uint32_t) * (c->nv ? c->nv : 1));
    if (!e || !owner || !w->adj_start || !w->vstart || !w->vlist) {
        free(e);
        free(owner);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    uint32_t ne = 0;
    for (uint32_t i = 0; i < s->edge_count; ++i) {
        uint32_t a = s->edges[2 * i], b = s->edges[2 * i + 1];
        if (a >= n || b >= n) {
            free(e);
            free(owner);
            return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_CGAL,
                                  "skeleton from mesh: CGAL edge %u refers to node %u of %u", i, a > b ? a : b, n);
        }
        if (a == b)
            continue;
        if (a > b) {
            const uint32_t t = a;
            a = b;
            b = t;
        }
        e[ne++] = (uint64_t)a << 32 | b;
    }
    qsort(e, ne, sizeof(uint64_t), cmp_u64);
    uint32_t nu = 0;
    for (uint32_t i = 0; i < ne; ++i)
        if (i == 0 || e[i] != e[i - 1])
            e[nu++] = e[i];
    w->edges = nu;
    w->adj = malloc(sizeof(uint32_t) * 2 * (nu ? nu : 1));
    if (!w->adj) {
        free(e);
        free(owner);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    for (uint32_t i = 0; i < nu; ++i) {
        w->adj_start[(e[i] >> 32) + 1]++;
        w->adj_start[(uint32_t)e[i] + 1]++;
    }
    for (uint32_t i = 0; i < n; ++i)
        w->adj_start[i + 1] += w->adj_start[i];
    /* Two passes over the sorted edges: first every node's smaller
     * neighbours, then its larger ones, so each list comes out sorted. */
    uint32_t* fill = malloc(sizeof(uint32_t) * (n ? n : 1));
    if (!fill) {
        free(e);
        free(owner);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    memcpy(fill, w->adj_start, sizeof(uint32_t) * n);
    for (uint32_t i = 0; i < nu; ++i) /* b's neighbours a < b, in increasing a */
        w->adj[fill[(uint32_t)e[i]]++] = (uint32_t)(e[i] >> 32);
    for (uint32_t i = 0; i < nu; ++i) /* then a's neighbours b > a, in increasing b */
        w->adj[fill[e[i] >> 32]++] = (uint32_t)e[i];
    free(fill);
    free(e);

    for (uint32_t v = 0; v < c->nv; ++v)
        owner[v] = UINT32_MAX;
    for (uint32_t i = 0; i < n; ++i)
        for (uint32_t k = s->corr_offset[i]; k < s->corr_offset[i + 1]; ++k) {
            const uint32_t v = s->corr[k];
            if (v >= c->nv) {
                free(owner);
                return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_CGAL,
                                      "skeleton from mesh: CGAL maps node %u to vertex %u of %u", i, v, c->nv);
            }
            if (owner[v] == UINT32_MAX)
                owner[v] = i;
        }
    w->unmapped = 0;
    for (uint32_t v = 0; v < c->nv; ++v)
        if (owner[v] == UINT32_MAX) {
            double best = DBL_MAX;
            for (uint32_t i = 0; i < n; ++i) {
                const double d = dist3(c->xyz + 3 * (size_t)v, s->xyz + 3 * (size_t)i);
                if (d < best) {
                    best = d;
                    owner[v] = i;
                }
            }
            w->unmapped++;
        }
    for (uint32_t v = 0; v < c->nv; ++v)
        w->vstart[owner[v] + 1]++;
    for (uint32_t i = 0; i < n; ++i)
        w->vstart[i + 1] += w->vstart[i];
    for (uint32_t v = 0; v < c->nv; ++v) /* in vertex order; vstart is the cursor, then shifts back */
        w->vlist[w->vstart[owner[v]]++] = v;
    for (uint32_t i = n; i > 0; --i)
        w->vstart[i] = w->vstart[i - 1];
    w->vstart[0] = 0;
    free(owner);
    return MESO_OK;
}

/* >>radii --------------------------------------------------------------- */

/* Per CGAL node: mean distance of its vertices to the nearest incident edge
 * (see the header). Nodes without vertices: mean of their neighbours' radii,
 * repeated until every node has one. */
static meso_result node_radii(const clean_mesh* c, const double* xyz, work_tree* w, meso_error* err)
{
    const uint32_t n = w->ncgal;
    uint8_t* has = calloc(n ? n : 1, 1);
    if (!has)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    uint32_t missing = 0;
    for (uint32_t i = 0; i < n; ++i) {
        const double* x = xyz + 3 * (size_t)i;
        double sum = 0;
        for (uint32_t k = w->vstart[i]; k < w->vstart[i + 1]; ++k) {
            const double* p = c->xyz + 3 * (size_t)w->vlist[k];
            double d = dist3(p, x);
            for (uint32_t j = w->adj_start[i]; j < w->adj_start[i + 1]; ++j) {
                const double dj = dist_segment(x, xyz + 3 * (size_t)w->adj[j], p);
                d = dj < d ? dj : d;
            }
            sum += d;
        }
        const uint32_t cnt = w->vstart[i + 1] - w->vstart[i];
        w->rad[i] = cnt ? sum / cnt : 0;
        has[i] = cnt > 0;
        missing += !cnt;
    }
    while (missing) {
        uint32_t filled = 0;
        for (uint32_t i = 0; i < n; ++i) {
            if (has[i])
                continue;
            double sum = 0;
            uint32_t cnt = 0;
            for (uint32_t j = w->adj_start[i]; j < w->adj_start[i + 1]; ++j)
                if (has[w->adj[j]] == 1) {
                    sum += w->rad[w->adj[j]];
                    ++cnt;
                }
            if (cnt) {
                w->rad[i] = sum / cnt;
                has[i] = 2; /* filled this round: not a source until the next */
                ++filled;
            }
        }
        if (!filled)
            break; /* a component without any vertex: radius 0 */
        for (uint32_t i = 0; i < n; ++i)
            has[i] = has[i] ? 1 : 0;
        missing -= filled;
    }
    free(has);
    return MESO_OK;
}

/* Node i is a better root than j (UINT32_MAX: none yet): larger radius,
 * then lower index. */
static inline int thicker(const double* rad, uint32_t i, uint32_t j)
{
    return j == UINT32_MAX || rad[i] > rad[j] || (rad[i] == rad[j] && i < j);
}

/* Spanning forest of the CGAL graph (breadth first from each component's
 * root, neighbours in index order); every non-tree edge adds a copied tip. */
static meso_result build_tree(work_tree* w, meso_error* err)
{
    const uint32_t n = w->ncgal;
    const size_t cap = (size_t)n + w->edges; /* at most one copy per edge */
    uint32_t* queue = malloc(sizeof(uint32_t) * (n ? n : 1));
    uint32_t* rank = malloc(sizeof(uint32_t) * (n ? n : 1));
    uint32_t* roots = malloc(sizeof(uint32_t) * (n ? n : 1));
    w->parent = malloc(sizeof(int32_t) * cap);
    w->src = malloc(sizeof(uint32_t) * cap);
    w->cstart = calloc(cap + 1, sizeof(uint32_t));
    w->child = malloc(sizeof(uint32_t) * cap);
    double* pos = realloc(w->pos, sizeof(double) * 3 * cap);
    if (pos)
        w->pos = pos;
    double* rad = realloc(w->rad, sizeof(double) * cap);
    if (rad)
        w->rad = rad;
    if (!queue || !rank || !roots || !w->parent || !w->src || !w->cstart || !w->child || !pos || !rad) {
        free(queue);
        free(rank);
        free(roots);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    for (uint32_t i = 0; i < n; ++i) {
        rank[i] = UINT32_MAX;
        w->src[i] = i;
        w->parent[i] = -1;
    }
    /* Components in index order of their first node; a root for each. The
     * flood fill marks with rank = 0 (reset before the trees are grown). */
    uint32_t nroots = 0;
    for (uint32_t s = 0; s < n; ++s) {
        if (rank[s] != UINT32_MAX)
            continue;
        uint32_t head = 0, tail = 0, root = UINT32_MAX, ring_root = UINT32_MAX;
        rank[s] = 0;
        queue[tail++] = s;
        while (head < tail) {
            const uint32_t i = queue[head++], deg = w->adj_start[i + 1] - w->adj_start[i];
            if (deg != 2 && thicker(w->rad, i, root))
                root = i;
            if (thicker(w->rad, i, ring_root))
                ring_root = i;
            for (uint32_t k = w->adj_start[i]; k < w->adj_start[i + 1]; ++k)
                if (rank[w->adj[k]] == UINT32_MAX) {
                    rank[w->adj[k]] = 0;
                    queue[tail++] = w->adj[k];
                }
        }
        roots[nroots++] = root != UINT32_MAX ? root : ring_root;
    }
    for (uint32_t i = 0; i < n; ++i)
        rank[i] = UINT32_MAX;
    uint32_t visited = 0;
    for (uint32_t r = 0; r < nroots; ++r) {
        uint32_t head = 0, tail = 0;
        rank[roots[r]] = visited++;
        queue[tail++] = roots[r];
        while (head < tail) {
            const uint32_t i = queue[head++];
            for (uint32_t k = w->adj_start[i]; k < w->adj_start[i + 1]; ++k) {
                const uint32_t j = w->adj[k];
                if (rank[j] == UINT32_MAX) {
                    rank[j] = visited++;
                    w->parent[j] = (int32_t)i;
                    queue[tail++] = j;
                }
            }
        }
    }
    /* Non-tree edges {a, b}: a copy of the later-visited end hangs on the other. */
    uint32_t nw = n;
    for (uint32_t a = 0; a < n; ++a)
        for (uint32_t k = w->adj_start[a]; k < w->adj_start[a + 1]; ++k) {
            const uint32_t b = w->adj[k];
            if (b < a || w->parent[b] == (int32_t)a || w->parent[a] == (int32_t)b)
                continue;
            const uint32_t later = rank[a] > rank[b] ? a : b, earlier = later == a ? b : a;
            memcpy(w->pos + 3 * (size_t)nw, w->pos + 3 * (size_t)later, sizeof(double) * 3);
            w->rad[nw] = w->rad[later];
            w->src[nw] = later;
            w->parent[nw] = (int32_t)earlier;
            ++nw;
        }
    w->n = nw;
    w->cycles = nw - n;
    w->roots = nroots;
    for (uint32_t i = 0; i < nw; ++i)
        if (w->parent[i] >= 0)
            w->cstart[w->parent[i] + 1]++;
    for (uint32_t i = 0; i < nw; ++i)
        w->cstart[i + 1] += w->cstart[i];
    memcpy(rank, w->cstart, sizeof(uint32_t) * (n < nw ? n : nw)); /* fill cursors for CGAL nodes */
    for (uint32_t i = 0; i < nw; ++i) {
        const int32_t p = w->parent[i];
        if (p >= 0)
            w->child[rank[p]++] = i; /* copies are leaves, so every parent is a CGAL node */
    }
    free(queue);
    free(rank);
    free(roots);
    return MESO_OK;
}

/* >>model --------------------------------------------------------------- */

/* The union of round-ended frusta as pieces: a ball per node, a truncated
 * cone per segment, each with a bounding sphere (centre c, radius bound). */
typedef struct piece {
    double a[3], b[3];
    double ra, rb;
    double c[3], bound;
    int ball;
    uint32_t node; /* the ball's node, or the segment's child end */
} piece;

typedef struct model {
    piece* p;
    uint32_t n;
} model;

/* Pieces of the nodes with keep[i] (all when keep is NULL): x holds 4
 * doubles per node (position, radius), parent[i] the node's parent (< 0:
 * none). `md` must have room for 2 n pieces (model_alloc). */
static void model_fill(const double* x, const int32_t* parent, const uint8_t* keep, uint32_t n, model* md)
{
    md->n = 0;
    for (uint32_t i = 0; i < n; ++i) {
        if (keep && !keep[i])
            continue;
        const double* xi = x + 4 * (size_t)i;
        piece* b = &md->p[md->n++];
        memcpy(b->a, xi, sizeof(b->a));
        memcpy(b->b, xi, sizeof(b->b));
        memcpy(b->c, xi, sizeof(b->c));
        b->ra = b->rb = b->bound = xi[3];
        b->ball = 1;
        b->node = i;
        if (parent[i] < 0)
            continue;
        const double* xj = x + 4 * (size_t)parent[i];
        piece* f = &md->p[md->n++];
        memcpy(f->a, xj, sizeof(f->a));
        memcpy(f->b, xi, sizeof(f->b));
        f->ra = xj[3];
        f->rb = xi[3];
        for (int k = 0; k < 3; ++k)
            f->c[k] = 0.5 * (f->a[k] + f->b[k]);
        f->bound = 0.5 * dist3(f->a, f->b) + (f->ra > f->rb ? f->ra : f->rb);
        f->ball = 0;
        f->node = i;
    }
}

static meso_result model_alloc(uint32_t n, model* md, meso_error* err)
{
    md->n = 0;
    md->p = malloc(sizeof(piece) * 2 * (size_t)(n ? n : 1));
    return md->p ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
}

static double piece_distance(const piece* q, const double p[3])
{
    return q->ball ? dist3(p, q->c) - q->ra : meso_cone_frustum_distance(q->a, q->ra, q->b, q->rb, p);
}

/* min over pieces of the signed distance, skipping pieces whose bounding
 * sphere proves them no closer; *hint (a piece index) is tried first and
 * updated to the minimiser (neighbouring queries share it). */
static double model_distance(const model* md, const double p[3], uint32_t* hint)
{
    const uint32_t h0 = *hint < md->n ? *hint : 0;
    uint32_t h = h0;
    double best = piece_distance(&md->p[h], p);
    for (uint32_t i = 0; i < md->n; ++i) {
        if (i == h0 || dist3(p, md->p[i].c) - md->p[i].bound >= best)
            continue;
        const double d = piece_distance(&md->p[i], p);
        if (d < best) {
            best = d;
            h = i;
        }
    }
    *hint = h;
    return best;
}

/* Mesh vertices -> model: largest and mean |signed distance|. */
static void mesh_to_model(const clean_mesh* c, const model* md, double* emax, double* emean)
{
    uint32_t hint = 0;
    double mx = 0, sum = 0;
    for (uint32_t v = 0; v < c->nv; ++v) {
        const double d = fabs(model_distance(md, c->xyz + 3 * (size_t)v, &hint));
        mx = d > mx ? d : mx;
        sum += d;
    }
    *emax = mx;
    *emean = c->nv ? sum / c->nv : 0;
}


/* >>mesh-distance ------------------------------------------------------- */

/* Exact distance from p to triangle (a, b, c): the closest point by Voronoi
 * regions (Ericson, "Real-Time Collision Detection", 5.1.5). */
static double point_triangle_distance(const double p[3], const double a[3], const double b[3], const double c[3])
{
    double ab[3], ac[3], ap[3], bp[3], cp[3], q[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    sub3(p, a, ap);
    const double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0)
        return dist3(p, a);
    sub3(p, b, bp);
    const double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3)
        return dist3(p, b);
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0)
        return dist_at(a, b, d1 / (d1 - d3), p);
    sub3(p, c, cp);
    const double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6)
        return dist3(p, c);
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0)
        return dist_at(a, c, d2 / (d2 - d6), p);
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return dist_at(b, c, (d4 - d3) / ((d4 - d3) + (d5 - d6)), p);
    const double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
    for (int k = 0; k < 3; ++k)
        q[k] = a[k] + ab[k] * v + ac[k] * w;
    return dist3(p, q);
}

/* Uniform grid of triangles (binned by their bounding boxes) for exact
 * nearest-triangle queries by growing shells of cells. */
typedef struct tri_grid {
    const clean_mesh* c;
    double lo[3], cell;
    int dim[3];
    uint32_t* start; /* dim[0]*dim[1]*dim[2] + 1 */
    uint32_t* items;
    uint32_t* stamp; /* per triangle: the last query that tested it */
    uint32_t query;
} tri_grid;

static void tri_grid_free(tri_grid* g)
{
    free(g->start);
    free(g->items);
    free(g->stamp);
}

static inline int grid_coord(const tri_grid* g, int k, double x)
{
    int i = (int)floor((x - g->lo[k]) / g->cell);
    return i < 0 ? 0 : i >= g->dim[k] ? g->dim[k] - 1 : i;
}

/* The grid covers [lo, hi] (the mesh and every query point). */
static meso_result tri_grid_build(const clean_mesh* c, const double lo[3], const double hi[3], tri_grid* g,
                                  meso_error* err)
{
    memset(g, 0, sizeof(*g));
    g->c = c;
    double ext = 0;
    for (int k = 0; k < 3; ++k)
        ext = hi[k] - lo[k] > ext ? hi[k] - lo[k] : ext;
    /* About one triangle per surface cell, at most 160 cells a side. */
    int res = (int)ceil(sqrt((double)c->nt));
    res = res < 4 ? 4 : res > 160 ? 160 : res;
    g->cell = ext > 0 ? ext / res : 1;
    for (int k = 0; k < 3; ++k) {
        g->lo[k] = lo[k];
        g->dim[k] = (int)floor((hi[k] - lo[k]) / g->cell) + 1;
    }
    const size_t cells = (size_t)g->dim[0] * g->dim[1] * g->dim[2];
    g->start = calloc(cells + 1, sizeof(uint32_t));
    g->stamp = calloc(c->nt ? c->nt : 1, sizeof(uint32_t));
    if (!g->start || !g->stamp)
        goto oom;
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t f = 0; f < c->nt; ++f) {
            int b0[3], b1[3];
            for (int k = 0; k < 3; ++k) {
                double mn = DBL_MAX, mx = -DBL_MAX;
                for (int j = 0; j < 3; ++j) {
                    const double x = c->xyz[3 * (size_t)c->tri[3 * f + j] + k];
                    mn = x < mn ? x : mn;
                    mx = x > mx ? x : mx;
                }
                b0[k] = grid_coord(g, k, mn);
                b1[k] = grid_coord(g, k, mx);
            }
            for (int z = b0[2]; z <= b1[2]; ++z)
                for (int y = b0[1]; y <= b1[1]; ++y)
                    for (int x = b0[0]; x <= b1[0]; ++x) {
                        const size_t cell = ((size_t)z * g->dim[1] + y) * g->dim[0] + x;
                        if (pass == 0)
                            g->start[cell + 1]++;
                        else
                            g->items[g->start[cell]++] = f;
                    }
        }
        if (pass == 0) {
            for (size_t i = 0; i < cells; ++i)
                g->start[i + 1] += g->start[i];
            g->items = malloc(sizeof(uint32_t) * (g->start[cells] ? g->start[cells] : 1));
            if (!g->items)
                goto oom;
        } else {
            for (size_t i = cells; i > 0; --i) /* the fill advanced each start to the next one's */
                g->start[i] = g->start[i - 1];
            g->start[0] = 0;
        }
    }
    return MESO_OK;
oom:
    tri_grid_free(g);
    return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
}

/* Unsigned distance from p to the mesh. After the cells within Chebyshev
 * distance k of p's cell are done, every other triangle is farther than
 * k * cell, so the search stops once the best is no more than that. */
static double tri_grid_distance(tri_grid* g, const double p[3])
{
    const clean_mesh* c = g->c;
    int ci[3];
    for (int k = 0; k < 3; ++k)
        ci[k] = grid_coord(g, k, p[k]);
    const int kmax = g->dim[0] > g->dim[1] ? (g->dim[0] > g->dim[2] ? g->dim[0] : g->dim[2])
                                            : (g->dim[1] > g->dim[2] ? g->dim[1] : g->dim[2]);
    double best = DBL_MAX;
    ++g->query;
    for (int k = 0; k <= kmax; ++k) {
        for (int z = ci[2] - k; z <= ci[2] + k; ++z) {
            if (z < 0 || z >= g->dim[2])
                continue;
            for (int y = ci[1] - k; y <= ci[1] + k; ++y) {
                if (y < 0 || y >= g->dim[1])
                    continue;
                const int shell_yz = abs(z - ci[2]) == k || abs(y - ci[1]) == k;
                for (int x = ci[0] - k; x <= ci[0] + k; x += shell_yz ? 1 : 2 * k) {
                    if (x >= 0 && x < g->dim[0]) {
                        const size_t cell = ((size_t)z * g->dim[1] + y) * g->dim[0] + x;
                        for (uint32_t i = g->start[cell]; i < g->start[cell + 1]; ++i) {
                            const uint32_t f = g->items[i];
                            if (g->stamp[f] == g->query)
                                continue;
                            g->stamp[f] = g->query;
                            const uint32_t* t = c->tri + 3 * (size_t)f;
                            const double d = point_triangle_distance(p, c->xyz + 3 * (size_t)t[0],
                                                                     c->xyz + 3 * (size_t)t[1], c->xyz + 3 * (size_t)t[2]);
                            best = d < best ? d : best;
                        }
                    }
                    if (k == 0)
                        break;
                }
            }
        }
        if (best <= k * g->cell)
            break;
    }
    return best;
}

/* Model -> mesh: points on the union's boundary (each piece's surface at
 * spacing ~h, kept when no other piece contains them) and their exact
 * distance to the mesh. Returns the largest; *count the points used. */
static meso_result model_to_mesh(const clean_mesh* c, const model* md, double h, double* out_max, uint32_t* count,
                                 meso_error* err)
{
    /* Bounds of the mesh and of every piece, for the grid. */
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (uint32_t v = 0; v < c->nv; ++v)
        for (int k = 0; k < 3; ++k) {
            const double x = c->xyz[3 * (size_t)v + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    for (uint32_t i = 0; i < md->n; ++i)
        for (int k = 0; k < 3; ++k) {
            const double l = md->p[i].c[k] - md->p[i].bound, u = md->p[i].c[k] + md->p[i].bound;
            lo[k] = l < lo[k] ? l : lo[k];
            hi[k] = u > hi[k] ? u : hi[k];
        }
    tri_grid g;
    meso_result r = tri_grid_build(c, lo, hi, &g, err);
    if (r != MESO_OK)
        return r;
    const double eps = 1e-9 * c->diag;
    double mx = 0;
    uint32_t used = 0;
    for (uint32_t i = 0; i < md->n; ++i) {
        const piece* q = &md->p[i];
        /* Axis frame (u, v, ax); a ball uses the z axis. */
        double ax[3] = {0, 0, 1}, u[3], v[3];
        double len = 0;
        if (!q->ball) {
            sub3(q->b, q->a, ax);
            if ((len = normalize3(ax)) <= 0)
                continue;
        }
        any_perp3(ax, u);
        cross3(ax, u, v);
        /* Rings: along the axis for a cone, over the polar angle for a ball. */
        const uint32_t rings = q->ball ? 1 + (uint32_t)ceil(M_PI * q->ra / h) : 1 + (uint32_t)ceil(len / h);
        for (uint32_t ri = 0; ri <= rings; ++ri) {
            const double s = (double)ri / rings;
            double centre[3], rr;
            if (q->ball) {
                const double th = M_PI * s;
                rr = q->ra * sin(th);
                for (int k = 0; k < 3; ++k)
                    centre[k] = q->c[k] + q->ra * cos(th) * ax[k];
            } else {
                rr = q->ra + (q->rb - q->ra) * s;
                for (int k = 0; k < 3; ++k)
                    centre[k] = q->a[k] + s * len * ax[k];
            }
            const uint32_t around = rr > 0 ? 1 + (uint32_t)ceil(2 * M_PI * rr / h) : 1;
            for (uint32_t ai = 0; ai < around; ++ai) {
                const double ph = 2 * M_PI * (ai + 0.5 * (ri & 1)) / around;
                double p[3];
                for (int k = 0; k < 3; ++k)
                    p[k] = centre[k] + rr * (cos(ph) * u[k] + sin(ph) * v[k]);
                int hidden = 0;
                for (uint32_t j = 0; j < md->n && !hidden; ++j)
                    hidden = j != i && dist3(p, md->p[j].c) - md->p[j].bound < -eps &&
                             piece_distance(&md->p[j], p) < -eps;
                if (hidden)
                    continue;
                const double d = tri_grid_distance(&g, p);
                mx = d > mx ? d : mx;
                ++used;
            }
        }
    }
    tri_grid_free(&g);
    *out_max = mx;
    *count = used;
    return MESO_OK;
}

/* Sample spacing for model_to_mesh: half the tolerance, coarsened so that
 * the pieces' total area holds at most ~30000 points. */
static double sample_spacing(const model* md, double tol)
{
    double area = 0;
    for (uint32_t i = 0; i < md->n; ++i) {
        const piece* q = &md->p[i];
        if (q->ball)
            area += 4 * M_PI * q->ra * q->ra;
        else
            area += M_PI * (q->ra + q->rb) * hypot(dist3(q->a, q->b), q->ra - q->rb);
    }
    const double h = 0.5 * tol, hmin = sqrt(area / 30000.0);
    return h > hmin ? h : hmin;
}

/* >>fit ----------------------------------------------------------------- */

/* The simplified skeleton is a subset of the working tree's nodes ("kept");
 * a segment is named by its child end b (its parent end is sparent[b]) and
 * holds the working nodes between them. Mesh vertices belong to segments
 * through their CGAL node. x holds each node's fitted position and radius
 * (copies mirror their originals, so a cut cycle stays closed). */
typedef struct fit_state {
    const clean_mesh* c;
    const work_tree* w;
    double tol;
    int refit;           /* least-squares positions and radii */
    uint32_t n;          /* working nodes */
    uint8_t* keep;       /* kept (output) nodes */
    uint8_t* fixed;      /* never merged away: the working tree's roots, tips and branch points, copies, their originals */
    uint8_t* nosplit;    /* per child end: no inner node left to split at */
    uint32_t* seg_child; /* per node: child end of the segment holding it (itself when kept) */
    int32_t* sparent;    /* per kept node: kept parent, -1 at a root */
    double* x;           /* 4 per node: position, radius */
    uint32_t* kstart;    /* kept children: kids[kstart[i] .. kstart[i+1]) */
    uint32_t* kids;
    uint32_t* owner;     /* per mesh vertex: its CGAL node */
    uint32_t* vseg;      /* per mesh vertex: child end of its segment; UINT32_MAX: its owner, a lone ball */
    double* verr;        /* per mesh vertex: |distance| to the model */
    uint32_t* vnear;     /* per mesh vertex: node of the model piece nearest to it (ball or child end) */
    double* segerr;      /* per child end: largest verr of its vertices */
    uint32_t* var;       /* per node: index of its unknowns (kept originals), else UINT32_MAX */
    uint32_t* path;      /* scratch, n */
    model md;
    /* Least squares scratch, sized for n unknown blocks of 4. */
    double *H, *E, *g, *dx, *r, *z, *d, *q, *xt, *kappa, *L;
    uint32_t* segs; /* child ends of the segments in the current system */
    uint32_t splits, merges;
} fit_state;

static void fit_state_free(fit_state* f)
{
    void* p[] = {f->keep, f->fixed, f->nosplit, f->seg_child, f->sparent, f->x, f->kstart, f->kids, f->owner, f->vseg,
                 f->verr, f->vnear, f->segerr, f->var, f->path, f->md.p, f->H, f->E, f->g, f->dx, f->r, f->z,
                 f->d, f->q, f->xt, f->segs, f->kappa, f->L};
    for (size_t i = 0; i < sizeof(p) / sizeof(p[0]); ++i)
        free(p[i]);
    memset(f, 0, sizeof(*f));
}

static inline uint32_t alias(const fit_state* f, uint32_t i)
{
    return i < f->w->ncgal ? i : f->w->src[i];
}

static inline int is_key(const work_tree* w, uint32_t i)
{
    return w->parent[i] < 0 || tree_degree(w, i) != 2;
}

/* Kept-children lists from sparent. */
static void rebuild_kids(fit_state* f)
{
    memset(f->kstart, 0, sizeof(uint32_t) * (f->n + 1));
    for (uint32_t i = 0; i < f->n; ++i)
        if (f->keep[i] && f->sparent[i] >= 0)
            f->kstart[f->sparent[i] + 1]++;
    for (uint32_t i = 0; i < f->n; ++i)
        f->kstart[i + 1] += f->kstart[i];
    memcpy(f->path, f->kstart, sizeof(uint32_t) * f->n);
    for (uint32_t i = 0; i < f->n; ++i)
        if (f->keep[i] && f->sparent[i] >= 0)
            f->kids[f->path[f->sparent[i]]++] = i;
}

/* Every vertex to a segment: its CGAL node's, or for a kept node's own
 * vertices the nearest segment at the node (by the current fit). */
static void assign_vertices(fit_state* f)
{
    rebuild_kids(f);
    for (uint32_t v = 0; v < f->c->nv; ++v) {
        const uint32_t o = f->owner[v];
        if (!f->keep[o]) {
            f->vseg[v] = f->seg_child[o];
            continue;
        }
        const double* p = f->c->xyz + 3 * (size_t)v;
        const double* xo = f->x + 4 * (size_t)o;
        double best = DBL_MAX;
        uint32_t seg = UINT32_MAX;
        if (f->sparent[o] >= 0) {
            best = dist_segment(f->x + 4 * (size_t)f->sparent[o], xo, p);
            seg = o;
        }
        for (uint32_t k = f->kstart[o]; k < f->kstart[o + 1]; ++k) {
            const double dk = dist_segment(xo, f->x + 4 * (size_t)f->kids[k], p);
            if (dk < best) {
                best = dk;
                seg = f->kids[k];
            }
        }
        f->vseg[v] = seg;
    }
}

/* Residual of vertex v under parameters xs: its distance to the axis point
 * of its segment minus the radius there (t clamped to the segment, so past
 * an end it is the end ball's). Gradient blocks (position, radius) for the
 * segment's parent end in ga and child end in gb; *na / *nb the nodes
 * (*nb = UINT32_MAX for a lone ball). */
static double residual(const fit_state* f, const double* xs, uint32_t v, double ga[4], double gb[4], uint32_t* na,
                       uint32_t* nb)
{
    const double* p = f->c->xyz + 3 * (size_t)v;
    const uint32_t b = f->vseg[v];
    double u[3], t = 0;
    const double *xa, *xb;
    if (b == UINT32_MAX) {
        *na = f->owner[v];
        *nb = UINT32_MAX;
        xa = xb = xs + 4 * (size_t)*na;
    } else {
        *na = (uint32_t)f->sparent[b];
        *nb = b;
        xa = xs + 4 * (size_t)*na;
        xb = xs + 4 * (size_t)b;
        t = seg_param(xa, xb, p);
        t = t < 0 ? 0 : t > 1 ? 1 : t;
    }
    for (int k = 0; k < 3; ++k)
        u[k] = p[k] - (xa[k] + t * (xb[k] - xa[k]));
    const double dl = sqrt(dot3(u, u));
    if (dl > 0)
        for (int k = 0; k < 3; ++k)
            u[k] /= dl;
    for (int k = 0; k < 3; ++k) {
        ga[k] = -(1 - t) * u[k];
        gb[k] = -t * u[k];
    }
    ga[3] = -(1 - t);
    gb[3] = -t;
    return dl - ((1 - t) * xa[3] + t * xb[3]);
}

/* Huber's loss (quadratic up to delta, then linear) and its IRLS weight:
 * vertices far from their segment's surface — a protrusion the segment
 * cannot have, or a correspondence CGAL got wrong at a junction — pull
 * with a bounded force instead of dragging the frustum to them. */
static inline double huber(double res, double delta)
{
    const double a = fabs(res);
    return a <= delta ? res * res : delta * (2 * a - delta);
}

static inline double huber_weight(double res, double delta)
{
    const double a = fabs(res);
    return a <= delta ? 1 : delta / a;
}

/* Robust cost plus the prior pulling positions to CGAL's. */
static double fit_cost(const fit_state* f, const double* xs)
{
    double cost = 0, ga[4], gb[4];
    uint32_t na, nb;
    for (uint32_t v = 0; v < f->c->nv; ++v)
        cost += huber(residual(f, xs, v, ga, gb, &na, &nb), f->tol);
    for (uint32_t i = 0; i < f->w->ncgal; ++i)
        if (f->var[i] != UINT32_MAX) {
            const double* k = f->kappa + 4 * (size_t)f->var[i];
            const double* xi = xs + 4 * (size_t)i;
            const double* p0 = f->w->pos + 3 * (size_t)i;
            const double dr = xi[3] - f->w->rad[i];
            cost += k[0] * (xi[0] - p0[0]) * (xi[0] - p0[0]) + k[1] * (xi[1] - p0[1]) * (xi[1] - p0[1]) +
                    k[2] * (xi[2] - p0[2]) * (xi[2] - p0[2]) + k[3] * dr * dr;
        }
    return cost;
}

static void add_outer(double* m, const double a[4], const double b[4])
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j < 4; ++j)
            m[4 * i + j] += a[i] * b[j];
}

/* Cholesky factor L (lower, row-major) of the 4x4 block h + mu diag(h) +
 * eps I (symmetric positive definite: eps > 0). */
static void block_cholesky(const double* h, double mu, double eps, double* L)
{
    for (int i = 0; i < 4; ++i)
        for (int j = 0; j <= i; ++j) {
            double sum = h[4 * i + j] + (i == j ? mu * h[5 * i] + eps : 0);
            for (int k = 0; k < j; ++k)
                sum -= L[4 * i + k] * L[4 * j + k];
            L[4 * i + j] = i == j ? sqrt(sum > eps ? sum : eps) : sum / L[5 * j];
        }
}

static void block_solve(const double* L, const double* b, double* x)
{
    double y[4];
    for (int i = 0; i < 4; ++i) {
        double sum = b[i];
        for (int k = 0; k < i; ++k)
            sum -= L[4 * i + k] * y[k];
        y[i] = sum / L[5 * i];
    }
    for (int i = 3; i >= 0; --i) {
        double sum = y[i];
        for (int k = i + 1; k < 4; ++k)
            sum -= L[4 * k + i] * x[k];
        x[i] = sum / L[5 * i];
    }
}

/* out = (H + mu diag(H) + eps) in, H block-sparse: H[nv] diagonal blocks,
 * E[s] the block of segment s between its parent end's unknowns (rows) and
 * its child end's (columns). */
static void lm_matvec(const fit_state* f, uint32_t nvar, uint32_t nseg, double mu, double eps, const double* in,
                      double* out)
{
    for (uint32_t v = 0; v < nvar; ++v)
        for (int i = 0; i < 4; ++i) {
            const double* h = f->H + 16 * (size_t)v + 4 * i;
            double s = (mu * h[i] + eps) * in[4 * v + i];
            for (int j = 0; j < 4; ++j)
                s += h[j] * in[4 * v + j];
            out[4 * v + i] = s;
        }
    for (uint32_t s = 0; s < nseg; ++s) {
        const uint32_t b = f->segs[s];
        const uint32_t va = f->var[alias(f, (uint32_t)f->sparent[b])], vb = f->var[alias(f, b)];
        const double* e = f->E + 16 * (size_t)s;
        for (int i = 0; i < 4; ++i)
            for (int j = 0; j < 4; ++j) {
                out[4 * va + i] += e[4 * i + j] * in[4 * vb + j];
                out[4 * vb + j] += e[4 * i + j] * in[4 * va + i];
            }
    }
}

/* Levenberg–Marquardt on all kept nodes' positions and radii, from CGAL's
 * positions and the per-node radii (so the result depends only on which
 * nodes are kept): minimise the Huber cost of the residuals plus a prior
 * sum_i kappa_i . (x_i - x_i(CGAL))^2 on positions and radii. Some
 * directions cost the data (almost) nothing — a node sliding along a
 * straight axis, the radius at the end of a segment whose vertices all lie
 * near its other end — and would wander (a radius grew to 2.6 on the
 * armadillo without the radius prior); the prior pins them. kappa is
 * MESO_SKELFIT_PRIOR x the larger of the node's own data curvature (per
 * position axis: trace / 3; radius: its diagonal entry) and the mean over
 * the nodes, so it biases well-determined moves by about that fraction and
 * holds data-poor nodes near CGAL. The normal system is solved by
 * conjugate gradients preconditioned with the 4x4 diagonal blocks. */
static void refit(fit_state* f, int iterations)
{
    if (!f->refit)
        return;
    for (uint32_t i = 0; i < f->n; ++i) {
        memcpy(f->x + 4 * (size_t)i, f->w->pos + 3 * (size_t)alias(f, i), sizeof(double) * 3);
        f->x[4 * (size_t)i + 3] = f->w->rad[alias(f, i)];
    }
    assign_vertices(f);
    uint32_t nvar = 0, nseg = 0;
    for (uint32_t i = 0; i < f->n; ++i)
        f->var[i] = f->keep[i] && i < f->w->ncgal ? nvar++ : UINT32_MAX;
    for (uint32_t i = f->w->ncgal; i < f->n; ++i) /* a kept copy's original is kept (pinned) */
        f->var[i] = f->var[alias(f, i)];
    for (uint32_t i = 0; i < f->n; ++i)
        if (f->keep[i] && f->sparent[i] >= 0)
            f->segs[nseg++] = i;
    uint32_t* segidx = f->path; /* per child end: its index in segs */
    for (uint32_t s = 0; s < nseg; ++s)
        segidx[f->segs[s]] = s;
    const size_t nu = 4 * (size_t)nvar;
    memset(f->kappa, 0, sizeof(double) * 4 * (nvar ? nvar : 1));
    double mu = 1e-3, cost = 0;
    for (int it = 0; it < iterations; ++it) {
        memset(f->H, 0, sizeof(double) * 16 * nvar);
        memset(f->E, 0, sizeof(double) * 16 * (nseg ? nseg : 1));
        memset(f->g, 0, sizeof(double) * nu);
        for (uint32_t v = 0; v < f->c->nv; ++v) {
            double ga[4], gb[4];
            uint32_t na, nb;
            double res = residual(f, f->x, v, ga, gb, &na, &nb);
            const double wt = sqrt(huber_weight(res, f->tol)); /* IRLS: scale the row by sqrt(w) */
            res *= wt;
            for (int k = 0; k < 4; ++k) {
                ga[k] *= wt;
                gb[k] *= wt;
            }
            const uint32_t va = f->var[na];
            if (nb == UINT32_MAX) { /* a lone ball: t = 0 */
                add_outer(f->H + 16 * (size_t)va, ga, ga);
                for (int k = 0; k < 4; ++k)
                    f->g[4 * va + k] += ga[k] * res;
                continue;
            }
            const uint32_t vb = f->var[nb];
            add_outer(f->H + 16 * (size_t)va, ga, ga);
            add_outer(f->H + 16 * (size_t)vb, gb, gb);
            add_outer(f->E + 16 * (size_t)segidx[nb], ga, gb);
            for (int k = 0; k < 4; ++k) {
                f->g[4 * va + k] += ga[k] * res;
                f->g[4 * vb + k] += gb[k] * res;
            }
        }
        if (it == 0) { /* the prior's weights, from the data at CGAL's positions */
            double mean_p = 0, mean_r = 0;
            for (uint32_t v = 0; v < nvar; ++v) {
                const double* h = f->H + 16 * (size_t)v;
                mean_p += (h[0] + h[5] + h[10]) / 3 / nvar;
                mean_r += h[15] / nvar;
            }
            for (uint32_t v = 0; v < nvar; ++v) {
                const double* h = f->H + 16 * (size_t)v;
                const double kp = (h[0] + h[5] + h[10]) / 3;
                for (int k = 0; k < 3; ++k)
                    f->kappa[4 * (size_t)v + k] = MESO_SKELFIT_PRIOR * (kp > mean_p ? kp : mean_p);
                f->kappa[4 * (size_t)v + 3] = MESO_SKELFIT_PRIOR * (h[15] > mean_r ? h[15] : mean_r);
            }
            cost = fit_cost(f, f->x);
        }
        for (uint32_t i = 0; i < f->w->ncgal; ++i) /* the prior's gradient and curvature */
            if (f->var[i] != UINT32_MAX) {
                const uint32_t v = f->var[i];
                for (int k = 0; k < 4; ++k) {
                    const double x0 = k < 3 ? f->w->pos[3 * (size_t)i + k] : f->w->rad[i];
                    f->g[4 * v + k] += f->kappa[4 * (size_t)v + k] * (f->x[4 * (size_t)i + k] - x0);
                    f->H[16 * (size_t)v + 5 * k] += f->kappa[4 * (size_t)v + k];
                }
            }
        double hmax = 0;
        for (uint32_t v = 0; v < nvar; ++v)
            for (int i = 0; i < 4; ++i)
                hmax = f->H[16 * (size_t)v + 5 * i] > hmax ? f->H[16 * (size_t)v + 5 * i] : hmax;
        const double eps = 1e-9 * hmax + 1e-300;
        int accepted = 0;
        for (int tries = 0; tries < 8 && !accepted; ++tries) {
            /* Solve (H + mu diag H + eps) dx = -g by conjugate gradients,
             * preconditioned by the damped 4x4 diagonal blocks (Cholesky). */
            for (uint32_t v = 0; v < nvar; ++v)
                block_cholesky(f->H + 16 * (size_t)v, mu, eps, f->L + 16 * (size_t)v);
            double rz = 0, g2 = 0;
            for (size_t i = 0; i < nu; ++i) {
                f->dx[i] = 0;
                f->r[i] = -f->g[i];
                g2 += f->g[i] * f->g[i];
            }
            for (uint32_t v = 0; v < nvar; ++v)
                block_solve(f->L + 16 * (size_t)v, f->r + 4 * (size_t)v, f->z + 4 * (size_t)v);
            for (size_t i = 0; i < nu; ++i) {
                f->d[i] = f->z[i];
                rz += f->r[i] * f->z[i];
            }
            for (int cg = 0; cg < MESO_SKELFIT_CG_ITERATIONS; ++cg) {
                double r2 = 0;
                for (size_t i = 0; i < nu; ++i)
                    r2 += f->r[i] * f->r[i];
                if (r2 <= 1e-20 * g2)
                    break;
                lm_matvec(f, nvar, nseg, mu, eps, f->d, f->q);
                double dq = 0;
                for (size_t i = 0; i < nu; ++i)
                    dq += f->d[i] * f->q[i];
                if (!(dq > 0))
                    break;
                const double alpha = rz / dq;
                for (size_t i = 0; i < nu; ++i) {
                    f->dx[i] += alpha * f->d[i];
                    f->r[i] -= alpha * f->q[i];
                }
                double rz1 = 0;
                for (uint32_t v = 0; v < nvar; ++v)
                    block_solve(f->L + 16 * (size_t)v, f->r + 4 * (size_t)v, f->z + 4 * (size_t)v);
                for (size_t i = 0; i < nu; ++i)
                    rz1 += f->r[i] * f->z[i];
                for (size_t i = 0; i < nu; ++i)
                    f->d[i] = f->z[i] + (rz1 / rz) * f->d[i];
                rz = rz1;
            }
            memcpy(f->xt, f->x, sizeof(double) * 4 * f->n);
            for (uint32_t i = 0; i < f->n; ++i)
                if (f->var[i] != UINT32_MAX) {
                    for (int k = 0; k < 4; ++k)
                        f->xt[4 * (size_t)i + k] += f->dx[4 * (size_t)f->var[i] + k];
                    if (f->xt[4 * (size_t)i + 3] < 0)
                        f->xt[4 * (size_t)i + 3] = 0;
                }
            const double trial = fit_cost(f, f->xt);
            if (trial < cost) {
                accepted = 1;
                const double gain = (cost - trial) / (cost > 0 ? cost : 1);
                memcpy(f->x, f->xt, sizeof(double) * 4 * f->n);
                cost = trial;
                mu = mu / 3 > 1e-9 ? mu / 3 : 1e-9;
                if (gain < 1e-6)
                    it = iterations; /* converged */
            } else
                mu *= 4;
        }
        if (!accepted)
            break;
    }
}

/* Distances of every vertex to the model, and each segment's worst. */
static void evaluate(fit_state* f)
{
    assign_vertices(f);
    model_fill(f->x, f->sparent, f->keep, f->n, &f->md);
    uint32_t hint = 0;
    for (uint32_t i = 0; i < f->n; ++i)
        f->segerr[i] = 0;
    for (uint32_t v = 0; v < f->c->nv; ++v) {
        f->verr[v] = fabs(model_distance(&f->md, f->c->xyz + 3 * (size_t)v, &hint));
        f->vnear[v] = f->md.p[hint].node;
        const uint32_t b = f->vseg[v];
        if (b != UINT32_MAX && f->verr[v] > f->segerr[b])
            f->segerr[b] = f->verr[v];
    }
}

/* Inner working nodes of segment b, from b's parent upwards, into path. */
static uint32_t segment_inner(const fit_state* f, uint32_t b)
{
    uint32_t m = 0;
    for (int32_t i = f->w->parent[b]; i >= 0 && i != f->sparent[b]; i = f->w->parent[i])
        f->path[m++] = (uint32_t)i;
    return m;
}

/* Split every segment whose worst vertex is beyond the tolerance at its
 * inner node with the worst vertex (the middle one if none has vertices).
 * Returns the number of splits. */
static uint32_t split_round(fit_state* f)
{
    uint32_t splits = 0;
    for (uint32_t b = 0; b < f->n; ++b) {
        if (!f->keep[b] || f->sparent[b] < 0 || f->nosplit[b] || !(f->segerr[b] > f->tol))
            continue;
        const uint32_t m = segment_inner(f, b);
        if (!m) {
            f->nosplit[b] = 1;
            continue;
        }
        uint32_t pick = f->path[m / 2];
        double worst = 0;
        for (uint32_t k = 0; k < m; ++k) {
            const uint32_t o = f->path[k];
            for (uint32_t q = f->w->vstart[o]; q < f->w->vstart[o + 1]; ++q) /* inner nodes are CGAL's, not copies */
                if (f->verr[f->w->vlist[q]] > worst) {
                    worst = f->verr[f->w->vlist[q]];
                    pick = o;
                }
        }
        const int32_t a = f->sparent[b];
        f->keep[pick] = 1;
        f->sparent[pick] = a;
        f->sparent[b] = (int32_t)pick;
        f->seg_child[pick] = pick;
        for (int32_t i = f->w->parent[pick]; i >= 0 && i != a; i = f->w->parent[i])
            f->seg_child[i] = pick;
        memcpy(f->x + 4 * (size_t)pick, f->w->pos + 3 * (size_t)pick, sizeof(double) * 3);
        f->x[4 * (size_t)pick + 3] = f->w->rad[pick];
        ++splits;
    }
    f->splits += splits;
    return splits;
}

/* Remove kept node x (not fixed: one kept child c, a kept parent): its
 * segments become one. */
static uint32_t merge_node(fit_state* f, uint32_t x)
{
    uint32_t c = UINT32_MAX;
    for (uint32_t i = 0; i < f->n && c == UINT32_MAX; ++i)
        if (f->keep[i] && f->sparent[i] == (int32_t)x)
            c = i;
    const int32_t a = f->sparent[x];
    f->keep[x] = 0;
    f->sparent[c] = a;
    f->seg_child[x] = c;
    for (int32_t i = f->w->parent[x]; i >= 0 && i != a; i = f->w->parent[i])
        f->seg_child[i] = c;
    return c;
}

/* How far x is from the segment its removal would make (ordering only). */
static double merge_estimate(const fit_state* f, uint32_t x)
{
    uint32_t c = UINT32_MAX;
    for (uint32_t i = 0; i < f->n && c == UINT32_MAX; ++i)
        if (f->keep[i] && f->sparent[i] == (int32_t)x)
            c = i;
    const double* xa = f->x + 4 * (size_t)f->sparent[x];
    const double* xc = f->x + 4 * (size_t)c;
    const double* xx = f->x + 4 * (size_t)x;
    double t = seg_param(xa, xc, xx);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return dist_at(xa, xc, t, xx) + fabs(xx[3] - ((1 - t) * xa[3] + t * xc[3]));
}

typedef struct merge_candidate {
    double estimate;
    uint32_t node;
} merge_candidate;

static int cmp_candidate(const void* a, const void* b)
{
    const merge_candidate *x = a, *y = b;
    if (x->estimate != y->estimate)
        return x->estimate < y->estimate ? -1 : 1;
    return x->node < y->node ? -1 : x->node > y->node;
}

/* Undo merge_node(f, x) that made c's parent a. */
static void unmerge_node(fit_state* f, uint32_t x, uint32_t c)
{
    const int32_t a = f->sparent[c];
    f->keep[x] = 1;
    f->sparent[x] = a;
    f->sparent[c] = (int32_t)x;
    f->seg_child[x] = x;
    for (int32_t i = f->w->parent[x]; i >= 0 && i != a; i = f->w->parent[i])
        f->seg_child[i] = x;
}

/* Greedy merging after the splits, which can overshoot: try removing each
 * removable node, cheapest first, at the fitted positions; keep the
 * removal when no vertex ends up beyond max(tolerance, its distance
 * before). The vertices checked are those whose distance can change: the
 * ones nearest to a removed piece or on the merged segments, and those
 * near enough to the new frustum to end up inside it. */
static meso_result merge_pass(fit_state* f, meso_error* err)
{
    const size_t n = f->n, nv = f->c->nv;
    merge_candidate* cand = malloc(sizeof(merge_candidate) * (n ? n : 1));
    uint32_t* hit = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    double* hit_err = malloc(sizeof(double) * (nv ? nv : 1));
    uint32_t* hit_near = malloc(sizeof(uint32_t) * (nv ? nv : 1));
    if (!cand || !hit || !hit_err || !hit_near) {
        free(cand), free(hit), free(hit_err), free(hit_near);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    const double slack = 1e-9 * f->c->diag;
    for (int pass = 0; pass < 4; ++pass) {
        uint32_t nc = 0, merged = 0;
        for (uint32_t i = 0; i < f->n; ++i)
            if (f->keep[i] && !f->fixed[i])
                cand[nc++] = (merge_candidate){merge_estimate(f, i), i};
        qsort(cand, nc, sizeof(merge_candidate), cmp_candidate);
        for (uint32_t k = 0; k < nc; ++k) {
            const uint32_t x = cand[k].node;
            const uint32_t c = merge_node(f, x);
            const double* xa = f->x + 4 * (size_t)f->sparent[c];
            const double* xc = f->x + 4 * (size_t)c;
            double mid[3];
            for (int q = 0; q < 3; ++q)
                mid[q] = 0.5 * (xa[q] + xc[q]);
            const double reach = 0.5 * dist3(xa, xc) + (xa[3] > xc[3] ? xa[3] : xc[3]) + f->tol;
            model_fill(f->x, f->sparent, f->keep, f->n, &f->md);
            uint32_t nh = 0, hint = 0;
            int ok = 1;
            for (uint32_t v = 0; v < nv && ok; ++v) {
                const double* p = f->c->xyz + 3 * (size_t)v;
                if (f->vnear[v] != x && f->vnear[v] != c && f->vseg[v] != x && f->vseg[v] != c && dist3(p, mid) > reach)
                    continue;
                const double d = fabs(model_distance(&f->md, p, &hint));
                ok = d <= (f->verr[v] > f->tol ? f->verr[v] : f->tol) + slack;
                hit[nh] = v;
                hit_err[nh] = d;
                hit_near[nh++] = f->md.p[hint].node;
            }
            if (!ok) {
                unmerge_node(f, x, c);
                continue;
            }
            for (uint32_t h = 0; h < nh; ++h) {
                f->verr[hit[h]] = hit_err[h];
                f->vnear[hit[h]] = hit_near[h];
            }
            for (uint32_t v = 0; v < nv; ++v)
                if (f->vseg[v] == x)
                    f->vseg[v] = c;
            ++merged;
        }
        f->merges += merged;
        if (!merged)
            break;
    }
    free(cand), free(hit), free(hit_err), free(hit_near);
    return MESO_OK;
}

static meso_result fit_state_init(fit_state* f, const clean_mesh* c, const work_tree* w, double tol, int refit_on,
                                  int all, meso_error* err)
{
    memset(f, 0, sizeof(*f));
    const size_t n = w->n;
    f->c = c;
    f->w = w;
    f->tol = tol;
    f->refit = refit_on;
    f->n = w->n;
    f->keep = calloc(n, 1);
    f->fixed = calloc(n, 1);
    f->nosplit = calloc(n, 1);
    f->seg_child = malloc(sizeof(uint32_t) * n);
    f->sparent = malloc(sizeof(int32_t) * n);
    f->x = malloc(sizeof(double) * 4 * n);
    f->xt = malloc(sizeof(double) * 4 * n);
    f->kstart = malloc(sizeof(uint32_t) * (n + 1));
    f->kids = malloc(sizeof(uint32_t) * n);
    f->var = malloc(sizeof(uint32_t) * n);
    f->path = malloc(sizeof(uint32_t) * n);
    f->segerr = malloc(sizeof(double) * n);
    f->segs = malloc(sizeof(uint32_t) * n);
    f->H = malloc(sizeof(double) * 16 * n);
    f->E = malloc(sizeof(double) * 16 * n);
    const size_t nu = 4 * n;
    f->g = malloc(sizeof(double) * nu);
    f->dx = malloc(sizeof(double) * nu);
    f->r = malloc(sizeof(double) * nu);
    f->z = malloc(sizeof(double) * nu);
    f->d = malloc(sizeof(double) * nu);
    f->q = malloc(sizeof(double) * nu);
    f->kappa = malloc(sizeof(double) * 4 * n);
    f->L = malloc(sizeof(double) * 16 * n);
    const size_t nv = c->nv ? c->nv : 1;
    f->owner = malloc(sizeof(uint32_t) * nv);
    f->vseg = malloc(sizeof(uint32_t) * nv);
    f->verr = malloc(sizeof(double) * nv);
    f->vnear = malloc(sizeof(uint32_t) * nv);
    if (model_alloc(w->n, &f->md, err) != MESO_OK || !f->keep || !f->fixed || !f->nosplit || !f->seg_child ||
        !f->sparent || !f->x || !f->xt || !f->kstart || !f->kids || !f->var || !f->path || !f->segerr || !f->segs ||
        !f->H || !f->E || !f->g || !f->dx || !f->r || !f->z || !f->d || !f->q || !f->kappa || !f->owner || !f->vseg || !f->verr ||
        !f->vnear || !f->L) {
        fit_state_free(f);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    for (uint32_t o = 0; o < w->ncgal; ++o)
        for (uint32_t k = w->vstart[o]; k < w->vstart[o + 1]; ++k)
            f->owner[w->vlist[k]] = o;
    for (uint32_t i = w->ncgal; i < w->n; ++i)
        f->fixed[i] = f->fixed[w->src[i]] = 1; /* copies and their originals */
    for (uint32_t i = 0; i < w->n; ++i) {
        memcpy(f->x + 4 * (size_t)i, w->pos + 3 * (size_t)i, sizeof(double) * 3);
        f->x[4 * (size_t)i + 3] = w->rad[i];
        f->fixed[i] = (uint8_t)(f->fixed[i] || is_key(w, i));
        f->keep[i] = (uint8_t)(all || f->fixed[i]);
        f->seg_child[i] = i;
    }
    for (uint32_t i = 0; i < w->n; ++i) {
        int32_t p = w->parent[i];
        while (p >= 0 && !f->keep[p])
            p = w->parent[p];
        f->sparent[i] = f->keep[i] ? p : -1;
        if (f->keep[i])
            for (int32_t j = w->parent[i]; j >= 0 && j != p; j = w->parent[j])
                f->seg_child[j] = i;
    }
    return MESO_OK;
}

static double max_error(const fit_state* f)
{
    double m = 0;
    for (uint32_t v = 0; v < f->c->nv; ++v)
        m = f->verr[v] > m ? f->verr[v] : m;
    return m;
}

/* Top-down: one segment per chain of the working tree, refit, then split
 * the segments beyond the tolerance and refit, until none is (or none can
 * be split); then merge what the splits overdid, and refit once more
 * (kept only if it does not make the largest error worse). */
static meso_result fit_skeleton(fit_state* f, int simplify, meso_error* err)
{
    if (!simplify) {
        evaluate(f);
        return MESO_OK;
    }
    refit(f, MESO_SKELFIT_LM_ITERATIONS);
    evaluate(f);
    for (int round = 0; round < 256 && split_round(f); ++round) {
        refit(f, MESO_SKELFIT_LM_ITERATIONS);
        evaluate(f);
    }
    meso_result r = merge_pass(f, err);
    if (r != MESO_OK || !f->merges || !f->refit) {
        evaluate(f);
        return r;
    }
    const double before = max_error(f);
    double* saved = malloc(sizeof(double) * 4 * f->n);
    if (!saved)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    memcpy(saved, f->x, sizeof(double) * 4 * f->n);
    refit(f, MESO_SKELFIT_LM_ITERATIONS);
    evaluate(f);
    const double after = max_error(f);
    if (after > before && after > f->tol) {
        memcpy(f->x, saved, sizeof(double) * 4 * f->n);
        evaluate(f);
    }
    free(saved);
    return MESO_OK;
}

/* >>output -------------------------------------------------------------- */

/* Kept nodes in depth-first preorder from each root (children by index). */
static meso_result make_output(const fit_state* f, meso_skeleton* out, meso_error* err)
{
    const uint32_t n = f->n;
    uint32_t nk = 0, nroots = 0;
    for (uint32_t i = 0; i < n; ++i)
        if (f->keep[i]) {
            ++nk;
            nroots += f->sparent[i] < 0;
        }
    if (nk > MESO_SKEL_MAX_NODES)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_CGAL, /* the mesh dictates it: exit 3 */
                              "skeleton from mesh: %u nodes, more than %u", nk, MESO_SKEL_MAX_NODES);
    out->nodes = calloc(nk ? nk : 1, sizeof(meso_skeleton_node));
    out->children = malloc(sizeof(uint32_t) * (nk - nroots ? nk - nroots : 1));
    uint32_t* stack = malloc(sizeof(uint32_t) * (n ? n : 1));
    uint32_t* index = malloc(sizeof(uint32_t) * (n ? n : 1));
    if (!out->nodes || !out->children || !stack || !index) {
        free(stack);
        free(index);
        meso_skeleton_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    }
    uint32_t next = 0;
    for (uint32_t root = 0; root < n; ++root) {
        if (!f->keep[root] || f->sparent[root] >= 0)
            continue;
        uint32_t top = 0;
        stack[top++] = root;
        while (top) {
            const uint32_t i = stack[--top];
            index[i] = next;
            meso_skeleton_node* nd = &out->nodes[next++];
            nd->id = next; /* index + 1 */
            memcpy(nd->pos, f->x + 4 * (size_t)i, sizeof(nd->pos));
            nd->radius = f->x[4 * (size_t)i + 3];
            nd->parent = f->sparent[i] >= 0 ? (int32_t)index[f->sparent[i]] : -1;
            for (uint32_t k = f->kstart[i + 1]; k > f->kstart[i]; --k) /* reversed: pop in index order */
                stack[top++] = f->kids[k - 1];
        }
    }
    /* Children grouped per parent, in node order: count, offsets, fill. */
    uint32_t* cnt = index;
    memset(cnt, 0, sizeof(uint32_t) * nk);
    for (uint32_t i = 0; i < nk; ++i)
        if (out->nodes[i].parent >= 0)
            cnt[out->nodes[i].parent]++;
    uint32_t first = 0;
    for (uint32_t i = 0; i < nk; ++i) {
        out->nodes[i].first_child = first;
        first += cnt[i];
    }
    for (uint32_t i = 0; i < nk; ++i) {
        const int32_t p = out->nodes[i].parent;
        if (p >= 0) {
            meso_skeleton_node* pn = &out->nodes[p];
            out->children[pn->first_child + pn->child_count++] = i;
        }
    }
    out->node_count = nk;
    out->root_count = nroots;
    free(stack);
    free(index);
    return MESO_OK;
}

/* >>main ---------------------------------------------------------------- */

static void cgal_skeleton_free(meso_cgal_skeleton* s)
{
    free(s->xyz);
    free(s->edges);
    free(s->corr_offset);
    free(s->corr);
    memset(s, 0, sizeof(*s));
}

/* CGAL, then the tree with per-node radii. */
static meso_result skeleton_tree(const clean_mesh* c, double medial_weight, work_tree* w, meso_skeleton_fit_stats* st,
                                 meso_error* err)
{
    meso_cgal_skeleton cs;
    const meso_cgal_skeleton_params params = {0, medial_weight};
    const double t0 = meso_seconds();
    meso_result r = meso_cgal_skeletonize(c->xyz, c->nv, c->tri, c->nt, &params, &cs, err);
    st->seconds_cgal = meso_seconds() - t0;
    if (r != MESO_OK) {
        if (err && !err->code)
            err->code = MESO_SKELFIT_ISSUE_CGAL;
        return r;
    }
    if (!cs.vertex_count) {
        cgal_skeleton_free(&cs);
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_SKELFIT_ISSUE_CGAL,
                              "skeleton from mesh: CGAL returned an empty skeleton");
    }
    w->pos = malloc(sizeof(double) * 3 * cs.vertex_count);
    w->rad = malloc(sizeof(double) * cs.vertex_count);
    if (!w->pos || !w->rad)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    else {
        memcpy(w->pos, cs.xyz, sizeof(double) * 3 * cs.vertex_count);
        r = take_cgal(c, &cs, w, err);
    }
    cgal_skeleton_free(&cs);
    if (r == MESO_OK)
        r = node_radii(c, w->pos, w, err);
    if (r == MESO_OK)
        r = build_tree(w, err);
    st->cgal_nodes = w->ncgal;
    st->cgal_edges = w->edges;
    st->cycles_broken = w->cycles;
    st->unmapped_vertices = w->unmapped;
    return r;
}

/* Fit error of CGAL's tree with the per-node radii (before anything else). */
static meso_result cgal_tree_error(const clean_mesh* c, const work_tree* w, meso_skeleton_fit_stats* st,
                                   meso_error* err)
{
    model md;
    double* x = malloc(sizeof(double) * 4 * (w->n ? w->n : 1));
    meso_result r = model_alloc(w->n, &md, err);
    if (r == MESO_OK && !x)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    if (r == MESO_OK) {
        for (uint32_t i = 0; i < w->n; ++i) {
            memcpy(x + 4 * (size_t)i, w->pos + 3 * (size_t)i, sizeof(double) * 3);
            x[4 * (size_t)i + 3] = w->rad[i];
        }
        model_fill(x, w->parent, NULL, w->n, &md);
        mesh_to_model(c, &md, &st->cgal_fit_error_max, &st->cgal_fit_error_mean);
    }
    free(x);
    free(md.p);
    return r;
}
#endif /* MESO_HAVE_CGAL */

meso_result meso_skeleton_from_mesh(const meso_mesh* mesh, const meso_skeleton_fit_options* opt, meso_skeleton* out,
                                    meso_skeleton_fit_stats* stats, meso_error* err)
{
    const double t0 = meso_seconds();
    meso_skeleton_fit_stats st;
    memset(&st, 0, sizeof(st));
    if (stats)
        *stats = st;
    if (out)
        memset(out, 0, sizeof(*out));
    if (!mesh || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "skeleton from mesh: NULL mesh or output");
    const meso_skeleton_fit_options o = opt ? *opt : (meso_skeleton_fit_options){0};
    if (o.fit < 0 || o.fit >= MESO_SKELFIT_COUNT || isnan(o.tolerance) || isnan(o.medial_weight))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "skeleton from mesh: bad options (fit %d, tolerance %g)",
                              o.fit, o.tolerance);
#if !MESO_HAVE_CGAL
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "skeleton from mesh: this build has no CGAL");
#else
    clean_mesh c;
    meso_result r = check_and_clean(mesh, &c, err);
    if (r != MESO_OK)
        return r;
    st.mesh_vertices = c.nv;
    st.mesh_triangles = c.nt;
    st.flipped = (uint32_t)c.flipped;
    st.bbox_diagonal = c.diag;
    st.tolerance = o.tolerance > 0 && isfinite(o.tolerance) ? o.tolerance : MESO_SKELFIT_DEFAULT_TOLERANCE * c.diag;

    work_tree w;
    memset(&w, 0, sizeof(w));
    fit_state f;
    memset(&f, 0, sizeof(f));
    r = skeleton_tree(&c, o.medial_weight > 0 ? o.medial_weight : MESO_SKELFIT_DEFAULT_MEDIAL_WEIGHT, &w, &st, err);
    if (r == MESO_OK)
        r = cgal_tree_error(&c, &w, &st, err);
    if (r == MESO_OK)
        r = fit_state_init(&f, &c, &w, st.tolerance, o.fit == MESO_SKELFIT_LSQ && !o.no_simplify, o.no_simplify,
                           err);
    if (r == MESO_OK)
        r = fit_skeleton(&f, !o.no_simplify, err);
    if (r == MESO_OK)
        r = make_output(&f, out, err);
    if (r == MESO_OK) {
        mesh_to_model(&c, &f.md, &st.fit_error_max, &st.fit_error_mean);
        r = model_to_mesh(&c, &f.md, sample_spacing(&f.md, st.tolerance), &st.model_to_mesh_max,
                          &st.surface_samples, err);
    }
    if (r == MESO_OK) {
        st.nodes = out->node_count;
        st.roots = out->root_count;
        st.segments = out->node_count - out->root_count;
        st.splits = f.splits;
        st.merges = f.merges;
        st.hausdorff = st.fit_error_max > st.model_to_mesh_max ? st.fit_error_max : st.model_to_mesh_max;
    } else
        meso_skeleton_free(out);
    fit_state_free(&f);
    work_tree_free(&w);
    clean_mesh_free(&c);
    st.seconds_total = meso_seconds() - t0;
    if (stats)
        *stats = st;
    return r;
#endif
}
