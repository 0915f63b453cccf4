/*
 * winding_number.c — generalized winding numbers, exact and hierarchical
 * (Barill et al. 2018). See winding_number.h for the method and its limits.
 */
#include "winding_number.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"
#include "vec3d.h"

#define FOUR_PI 12.566370614359172953850573533118
#define TWO_PI 6.283185307179586476925286766559
/* Traversal stack: a depth-first walk holds at most depth + 1 entries, and
 * the median split bounds the depth by ceil(log2(n / leaf)) + 1 < 32. */
#define MAX_DEPTH 64

typedef struct node {
    double centre[3]; /* p~: area-weighted centre of the triangles' centroids */
    double normal[3]; /* N = sum a_t n_t */
    double moment[9]; /* M = sum a_t n_t (c_t - p~)^T, row-major */
    double radius;    /* every vertex of the node lies within radius of p~ */
    uint32_t right;   /* internal: index of the right child (left is this + 1) */
    uint32_t first;   /* leaf: first triangle in leaf order */
    uint32_t count;   /* leaf: triangle count; 0 for internal nodes */
} node;

struct meso_winding {
    node* nodes;
    uint32_t node_count;
    uint32_t depth;
    uint32_t triangle_count;
    float* tris; /* 9 floats per triangle, in leaf order */
};

/* >>exact ----------------------------------------------------------------- */

double meso_winding_triangle(const double A[3], const double B[3], const double C[3], const double q[3])
{
    /* Van Oosterom & Strackee: tan(Omega / 2) = det[a b c] / (|a||b||c| +
     * (a.b)|c| + (a.c)|b| + (b.c)|a|), with a, b, c the corners relative to
     * q. atan2 keeps the quadrant, so Omega covers (-2 pi, 2 pi]. */
    double a[3], b[3], c[3];
    sub3(A, q, a);
    sub3(B, q, b);
    sub3(C, q, c);
    const double la = len3(a), lb = len3(b), lc = len3(c);
    const double det = a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0]) +
                       a[2] * (b[0] * c[1] - b[1] * c[0]);
    const double ab = dot3(a, b), ac = dot3(a, c), bc = dot3(b, c);
    const double den = la * lb * lc + ab * lc + ac * lb + bc * la;
    return atan2(det, den) / TWO_PI; /* (2 atan2) / (4 pi) */
}

static void corner(const float* p, uint32_t v, double out[3])
{
    out[0] = p[3 * (size_t)v];
    out[1] = p[3 * (size_t)v + 1];
    out[2] = p[3 * (size_t)v + 2];
}

double meso_winding_exact(const meso_mesh* m, const double q[3])
{
    double w = 0.0;
    for (uint32_t f = 0; f < m->triangle_count; ++f) {
        double a[3], b[3], c[3];
        corner(m->positions, m->indices[3 * (size_t)f], a);
        corner(m->positions, m->indices[3 * (size_t)f + 1], b);
        corner(m->positions, m->indices[3 * (size_t)f + 2], c);
        w += meso_winding_triangle(a, b, c, q);
    }
    return w;
}

/* >>build ----------------------------------------------------------------- */

typedef struct builder {
    const meso_mesh* m;
    uint32_t* order;   /* triangle indices, permuted into leaf order */
    double* centroid;  /* 3 per triangle */
    double* anormal;   /* 3 per triangle: area * unit normal (= cross / 2) */
    double* area;      /* 1 per triangle */
    node* nodes;
    uint32_t node_count;
    uint32_t depth;
} builder;

/* Strict total order on triangles along one axis: centroid, then index. */
static int before(const builder* b, int axis, uint32_t s, uint32_t t)
{
    const double ks = b->centroid[3 * (size_t)s + axis], kt = b->centroid[3 * (size_t)t + axis];
    return ks < kt || (ks == kt && s < t);
}

static void swap_u32(uint32_t* x, size_t i, size_t j)
{
    const uint32_t t = x[i];
    x[i] = x[j];
    x[j] = t;
}

/* Quickselect: afterwards order[k] is the k-th triangle of [lo, hi) by
 * `before`, with smaller ones left of it and larger ones right. Median-of-
 * three pivots; the keys are distinct (index tie-break), so Lomuto
 * partitioning does not degrade on equal centroids. Deterministic. */
static void select_kth(const builder* b, int axis, size_t lo, size_t hi, size_t k)
{
    uint32_t* o = b->order;
    while (hi - lo > 1) {
        const size_t mid = lo + (hi - lo) / 2, last = hi - 1;
        if (before(b, axis, o[mid], o[lo]))
            swap_u32(o, mid, lo);
        if (before(b, axis, o[last], o[lo]))
            swap_u32(o, last, lo);
        if (before(b, axis, o[last], o[mid]))
            swap_u32(o, last, mid);
        swap_u32(o, mid, last); /* median to the end as the pivot */
        const uint32_t pivot = o[last];
        size_t store = lo;
        for (size_t i = lo; i < last; ++i)
            if (before(b, axis, o[i], pivot))
                swap_u32(o, i, store++);
        swap_u32(o, store, last);
        if (k == store)
            return;
        if (k < store)
            hi = store;
        else
            lo = store + 1;
    }
}

/* Builds the subtree of triangles order[lo..hi) at nodes[b->node_count],
 * depth-first (left child right after its parent). */
static uint32_t build_node(builder* b, size_t lo, size_t hi, uint32_t depth)
{
    const uint32_t id = b->node_count++;
    node* nd = &b->nodes[id];
    memset(nd, 0, sizeof(*nd));
    if (depth > b->depth)
        b->depth = depth;

    /* Moments about the area-weighted centre. */
    double asum = 0.0, ac[3] = {0, 0, 0}, cmean[3] = {0, 0, 0};
    double clo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, chi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (size_t i = lo; i < hi; ++i) {
        const uint32_t t = b->order[i];
        const double* c = &b->centroid[3 * (size_t)t];
        for (int k = 0; k < 3; ++k) {
            ac[k] += b->area[t] * c[k];
            cmean[k] += c[k];
            nd->normal[k] += b->anormal[3 * (size_t)t + k];
            clo[k] = c[k] < clo[k] ? c[k] : clo[k];
            chi[k] = c[k] > chi[k] ? c[k] : chi[k];
        }
        asum += b->area[t];
    }
    for (int k = 0; k < 3; ++k) /* all-degenerate nodes: the plain centroid mean */
        nd->centre[k] = asum > 0.0 ? ac[k] / asum : cmean[k] / (double)(hi - lo);
    double r2 = 0.0;
    for (size_t i = lo; i < hi; ++i) {
        const uint32_t t = b->order[i];
        const double* c = &b->centroid[3 * (size_t)t];
        const double* an = &b->anormal[3 * (size_t)t];
        for (int r = 0; r < 3; ++r)
            for (int k = 0; k < 3; ++k)
                nd->moment[3 * r + k] += an[r] * (c[k] - nd->centre[k]);
        for (int v = 0; v < 3; ++v) {
            double p[3], d[3];
            corner(b->m->positions, b->m->indices[3 * (size_t)t + v], p);
            sub3(p, nd->centre, d);
            const double d2 = dot3(d, d);
            r2 = d2 > r2 ? d2 : r2;
        }
    }
    nd->radius = sqrt(r2);

    if (hi - lo <= MESO_WINDING_LEAF_SIZE) {
        nd->first = (uint32_t)lo;
        nd->count = (uint32_t)(hi - lo);
        return id;
    }
    int axis = 0;
    for (int k = 1; k < 3; ++k)
        if (chi[k] - clo[k] > chi[axis] - clo[axis])
            axis = k;
    const size_t mid = lo + (hi - lo) / 2;
    select_kth(b, axis, lo, hi, mid);
    build_node(b, lo, mid, depth + 1);
    const uint32_t right = build_node(b, mid, hi, depth + 1);
    nd->right = right; /* nodes[] was sized up front: nd is still valid */
    return id;
}

meso_result meso_winding_build(const meso_mesh* m, int threads, meso_winding** out, meso_error* err)
{
    (void)threads;
    if (!out || !m)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "winding number: NULL argument");
    *out = NULL;
    if (m->triangle_count == 0 || m->vertex_count == 0 || !m->positions || !m->indices)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_WINDING_ISSUE_EMPTY,
                              "winding number: the mesh has no triangles (%u vertices, %u triangles)", m->vertex_count,
                              m->triangle_count);
    for (size_t i = 0; i < 3 * (size_t)m->vertex_count; ++i)
        if (!isfinite(m->positions[i]))
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_WINDING_ISSUE_NONFINITE,
                                  "winding number: vertex %zu has a non-finite coordinate", i / 3);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; ++i)
        if (m->indices[i] >= m->vertex_count)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_WINDING_ISSUE_INDEX,
                                  "winding number: face %zu refers to vertex %u of %u", i / 3, m->indices[i],
                                  m->vertex_count);

    const size_t n = m->triangle_count;
    /* A binary tree with leaves of >= 1 triangle has < 2 n nodes. */
    const size_t max_nodes = 2 * n;
    builder b = {.m = m};
    b.order = malloc(sizeof(uint32_t) * n);
    b.centroid = malloc(sizeof(double) * 3 * n);
    b.anormal = malloc(sizeof(double) * 3 * n);
    b.area = malloc(sizeof(double) * n);
    b.nodes = malloc(sizeof(node) * max_nodes);
    meso_winding* t = calloc(1, sizeof(*t));
    if (t)
        t->tris = malloc(sizeof(float) * 9 * n);
    if (!b.order || !b.centroid || !b.anormal || !b.area || !b.nodes || !t || !t->tris) {
        free(b.order);
        free(b.centroid);
        free(b.anormal);
        free(b.area);
        free(b.nodes);
        if (t)
            free(t->tris);
        free(t);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "winding number: out of memory (%zu triangles)", n);
    }
    for (size_t f = 0; f < n; ++f) {
        double p[3][3];
        for (int v = 0; v < 3; ++v)
            corner(m->positions, m->indices[3 * f + v], p[v]);
        double e1[3], e2[3], cr[3];
        sub3(p[1], p[0], e1);
        sub3(p[2], p[0], e2);
        cross3(e1, e2, cr);
        for (int k = 0; k < 3; ++k) {
            b.centroid[3 * f + k] = (p[0][k] + p[1][k] + p[2][k]) / 3.0;
            b.anormal[3 * f + k] = 0.5 * cr[k];
        }
        b.area[f] = 0.5 * len3(cr);
        b.order[f] = (uint32_t)f;
    }
    build_node(&b, 0, n, 0);

    t->triangle_count = (uint32_t)n;
    t->node_count = b.node_count;
    t->depth = b.depth;
    for (size_t i = 0; i < n; ++i)
        for (int v = 0; v < 3; ++v)
            memcpy(&t->tris[9 * i + 3 * v], &m->positions[3 * (size_t)m->indices[3 * (size_t)b.order[i] + v]],
                   3 * sizeof(float));
    t->nodes = realloc(b.nodes, sizeof(node) * b.node_count);
    if (!t->nodes) /* shrinking failed: keep the larger block */
        t->nodes = b.nodes;
    free(b.order);
    free(b.centroid);
    free(b.anormal);
    free(b.area);
    *out = t;
    return MESO_OK;
}

/* >>query ----------------------------------------------------------------- */

double meso_winding_query(const meso_winding* t, const double q[3])
{
    uint32_t stack[MAX_DEPTH + 2];
    uint32_t top = 0;
    double w = 0.0;
    stack[top++] = 0;
    while (top > 0) {
        const node* nd = &t->nodes[stack[--top]];
        double r[3];
        sub3(nd->centre, q, r);
        const double d2 = dot3(r, r);
        const double br = MESO_WINDING_BETA * nd->radius;
        if (d2 > br * br) {
            /* Far field about p~ with r = p~ - q, G'(r) = r / (4 pi |r|^3):
             *   order 1   N . r / (4 pi d^3)
             *   order 2   (tr M / d^3 - 3 r^T M r / d^5) / (4 pi)
             * (Barill et al. 2018, eq. 11 with the Hessian of the Green's
             * function written out). */
            const double d = sqrt(d2), inv3 = 1.0 / (d2 * d), inv5 = inv3 / d2;
            const double* M = nd->moment;
            const double w1 = dot3(nd->normal, r) * inv3;
            const double Mr[3] = {dot3(M, r), dot3(M + 3, r), dot3(M + 6, r)};
            const double rMr = dot3(r, Mr);
            const double w2 = (M[0] + M[4] + M[8]) * inv3 - 3.0 * rMr * inv5;
            w += (w1 + w2) / FOUR_PI;
        } else if (nd->count > 0) {
            for (uint32_t i = nd->first; i < nd->first + nd->count; ++i) {
                const float* p = &t->tris[9 * (size_t)i];
                const double a[3] = {p[0], p[1], p[2]}, b[3] = {p[3], p[4], p[5]}, c[3] = {p[6], p[7], p[8]};
                w += meso_winding_triangle(a, b, c, q);
            }
        } else {
            const uint32_t self = (uint32_t)(nd - t->nodes);
            stack[top++] = nd->right; /* left first: pushed last */
            stack[top++] = self + 1;
        }
    }
    return w;
}

void meso_winding_query_many(const meso_winding* t, const double* xyz, size_t count, double* w, int threads)
{
    const int nt = meso_bake_thread_count(threads);
    (void)nt;
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 256) num_threads(nt)
#endif
    for (ptrdiff_t i = 0; i < (ptrdiff_t)count; ++i)
        w[i] = meso_winding_query(t, &xyz[3 * (size_t)i]);
}

void meso_winding_stats(const meso_winding* t, uint32_t* nodes, uint32_t* depth)
{
    if (nodes)
        *nodes = t ? t->node_count : 0;
    if (depth)
        *depth = t ? t->depth : 0;
}

void meso_winding_free(meso_winding* t)
{
    if (!t)
        return;
    free(t->nodes);
    free(t->tris);
    free(t);
}
