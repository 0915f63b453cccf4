/*
 * skeleton_tree.c — stages 2-4 of meso_skeleton_from_mesh: CGAL's
 * mean-curvature-flow skeleton (Tagliasacchi et al. 2012, through
 * meso_cgal_skeletonize) as a graph with its vertex correspondence, a radius
 * per node, and the spanning tree the fit works on.
 *
 * From skeleton_from_mesh.h: each mesh vertex belongs to the node CGAL's
 * correspondence gives it (one listed nowhere, `unmapped_vertices`, to the
 * nearest node; one listed twice to the first). A node's radius is the mean
 * over its vertices of their distance to the nearest skeleton edge at the
 * node: the least-squares radius of the local tube, radial rather than to
 * the node; nodes without vertices take their neighbours' mean. The tree
 * grows breadth first from a root per component (largest radius among the
 * nodes of degree != 2, so the root does not split a chain; a ring: the
 * largest radius; ties: lowest index). Each edge left out of the tree (a
 * genus-g surface has g) becomes a copied tip, so the surface keeps every
 * frustum and only the tree's topology is cut (`cycles_broken`).
 */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "skeleton_from_mesh_internal.h"

void mesoi_work_tree_free(mesoi_work_tree* w)
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

static int cmp_u64(const void* a, const void* b)
{
    const uint64_t x = *(const uint64_t*)a, y = *(const uint64_t*)b;
    return x < y ? -1 : x > y;
}

/* CGAL's graph (deduplicated) and its correspondence, inverted to a
 * vertex -> node owner and regrouped. */
static meso_result take_cgal(const mesoi_clean_mesh* c, const meso_cgal_skeleton* s, mesoi_work_tree* w,
                             meso_error* err)
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
static meso_result node_radii(const mesoi_clean_mesh* c, const double* xyz, mesoi_work_tree* w, meso_error* err)
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
                const double dj = mesoi_dist_segment(x, xyz + 3 * (size_t)w->adj[j], p);
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
static meso_result build_tree(mesoi_work_tree* w, meso_error* err)
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

meso_result mesoi_work_tree_from_cgal(const mesoi_clean_mesh* c, const meso_cgal_skeleton* cs, mesoi_work_tree* w,
                                      meso_error* err)
{
    meso_result r;
    w->pos = malloc(sizeof(double) * 3 * cs->vertex_count);
    w->rad = malloc(sizeof(double) * cs->vertex_count);
    if (!w->pos || !w->rad)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    else {
        memcpy(w->pos, cs->xyz, sizeof(double) * 3 * cs->vertex_count);
        r = take_cgal(c, cs, w, err);
    }
    if (r == MESO_OK)
        r = node_radii(c, w->pos, w, err);
    if (r == MESO_OK)
        r = build_tree(w, err);
    return r;
}
