/*
 * skeleton_simplify.c — the simplification of stage 5 of
 * meso_skeleton_from_mesh: which of the working tree's nodes are kept, so
 * that every mesh vertex is within the tolerance of the model.
 *
 * From skeleton_from_mesh.h, 5. (top-down): start from one segment per chain
 * (a path between the working tree's roots, tips and branch points, which
 * all stay), fit (skeleton_radius_fit.c), and split every segment whose
 * worst vertex is beyond the tolerance at the inner CGAL node holding its
 * worst vertex; refit; repeat until no segment is beyond it or can be split
 * (a single CGAL edge). Then greedily merge kept nodes back (cheapest
 * first) wherever no vertex ends up beyond max(tolerance, its distance
 * before), and refit once more (kept unless it makes the largest error
 * worse). Not guaranteed minimal; the splits overshoot and the merges take
 * back about 2/3 of them. The tolerance is a target, not a guarantee: the
 * fit stops where a segment is a single CGAL edge.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "skeleton_from_mesh_internal.h"

/* Never merged away: a root, a tip or a branch point of the working tree. */
static inline int is_key(const mesoi_work_tree* w, uint32_t i)
{
    return w->parent[i] < 0 || mesoi_tree_degree(w, i) != 2;
}

/* Distances of every vertex to the model, and each segment's worst. */
static void evaluate(mesoi_fit_state* f)
{
    mesoi_skel_assign_vertices(f);
    mesoi_model_fill(f->x, f->sparent, f->keep, f->n, &f->md);
    uint32_t hint = 0;
    for (uint32_t i = 0; i < f->n; ++i)
        f->segerr[i] = 0;
    for (uint32_t v = 0; v < f->c->nv; ++v) {
        f->verr[v] = fabs(mesoi_model_distance(&f->md, f->c->xyz + 3 * (size_t)v, &hint));
        f->vnear[v] = f->md.p[hint].node;
        const uint32_t b = f->vseg[v];
        if (b != UINT32_MAX && f->verr[v] > f->segerr[b])
            f->segerr[b] = f->verr[v];
    }
}

/* Inner working nodes of segment b, from b's parent upwards, into path. */
static uint32_t segment_inner(const mesoi_fit_state* f, uint32_t b)
{
    uint32_t m = 0;
    for (int32_t i = f->w->parent[b]; i >= 0 && i != f->sparent[b]; i = f->w->parent[i])
        f->path[m++] = (uint32_t)i;
    return m;
}

/* Keep x, an inner node of segment c: the segment splits in two at x (a
 * split, or the undoing of merge_node(f, x)). */
static void insert_node(mesoi_fit_state* f, uint32_t x, uint32_t c)
{
    const int32_t a = f->sparent[c];
    f->keep[x] = 1;
    f->sparent[x] = a;
    f->sparent[c] = (int32_t)x;
    f->seg_child[x] = x;
    for (int32_t i = f->w->parent[x]; i >= 0 && i != a; i = f->w->parent[i])
        f->seg_child[i] = x;
}

/* Split every segment whose worst vertex is beyond the tolerance at its
 * inner node with the worst vertex (the middle one if none has vertices).
 * Returns the number of splits. */
static uint32_t split_round(mesoi_fit_state* f)
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
        insert_node(f, pick, b);
        memcpy(f->x + 4 * (size_t)pick, f->w->pos + 3 * (size_t)pick, sizeof(double) * 3);
        f->x[4 * (size_t)pick + 3] = f->w->rad[pick];
        ++splits;
    }
    f->splits += splits;
    return splits;
}

/* Remove kept node x (not fixed: one kept child c, a kept parent): its
 * segments become one. */
static uint32_t merge_node(mesoi_fit_state* f, uint32_t x)
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
static double merge_estimate(const mesoi_fit_state* f, uint32_t x)
{
    uint32_t c = UINT32_MAX;
    for (uint32_t i = 0; i < f->n && c == UINT32_MAX; ++i)
        if (f->keep[i] && f->sparent[i] == (int32_t)x)
            c = i;
    const double* xa = f->x + 4 * (size_t)f->sparent[x];
    const double* xc = f->x + 4 * (size_t)c;
    const double* xx = f->x + 4 * (size_t)x;
    double t = mesoi_seg_param(xa, xc, xx);
    t = t < 0 ? 0 : t > 1 ? 1 : t;
    return mesoi_dist_at(xa, xc, t, xx) + fabs(xx[3] - ((1 - t) * xa[3] + t * xc[3]));
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

/* Greedy merging after the splits, which can overshoot: try removing each
 * removable node, cheapest first, at the fitted positions; keep the
 * removal when no vertex ends up beyond max(tolerance, its distance
 * before). The vertices checked are those whose distance can change: the
 * ones nearest to a removed piece or on the merged segments, and those
 * near enough to the new frustum to end up inside it. */
static meso_result merge_pass(mesoi_fit_state* f, meso_error* err)
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
            mesoi_model_fill(f->x, f->sparent, f->keep, f->n, &f->md);
            uint32_t nh = 0, hint = 0;
            int ok = 1;
            for (uint32_t v = 0; v < nv && ok; ++v) {
                const double* p = f->c->xyz + 3 * (size_t)v;
                if (f->vnear[v] != x && f->vnear[v] != c && f->vseg[v] != x && f->vseg[v] != c && dist3(p, mid) > reach)
                    continue;
                const double d = fabs(mesoi_model_distance(&f->md, p, &hint));
                ok = d <= (f->verr[v] > f->tol ? f->verr[v] : f->tol) + slack;
                hit[nh] = v;
                hit_err[nh] = d;
                hit_near[nh++] = f->md.p[hint].node;
            }
            if (!ok) {
                insert_node(f, x, c);
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

meso_result mesoi_fit_state_init(mesoi_fit_state* f, const mesoi_clean_mesh* c, const mesoi_work_tree* w, double tol,
                                 int refit_on, int all, meso_error* err)
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
    if (mesoi_model_alloc(w->n, &f->md, err) != MESO_OK || !f->keep || !f->fixed || !f->nosplit || !f->seg_child ||
        !f->sparent || !f->x || !f->xt || !f->kstart || !f->kids || !f->var || !f->path || !f->segerr || !f->segs ||
        !f->H || !f->E || !f->g || !f->dx || !f->r || !f->z || !f->d || !f->q || !f->kappa || !f->owner || !f->vseg || !f->verr ||
        !f->vnear || !f->L) {
        mesoi_fit_state_free(f);
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

static double max_error(const mesoi_fit_state* f)
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
meso_result mesoi_fit_skeleton(mesoi_fit_state* f, int simplify, meso_error* err)
{
    if (!simplify) {
        evaluate(f);
        return MESO_OK;
    }
    mesoi_skel_refit(f, MESO_SKELFIT_LM_ITERATIONS);
    evaluate(f);
    for (int round = 0; round < 256 && split_round(f); ++round) {
        mesoi_skel_refit(f, MESO_SKELFIT_LM_ITERATIONS);
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
    mesoi_skel_refit(f, MESO_SKELFIT_LM_ITERATIONS);
    evaluate(f);
    const double after = max_error(f);
    if (after > before && after > f->tol) {
        memcpy(f->x, saved, sizeof(double) * 4 * f->n);
        evaluate(f);
    }
    free(saved);
    return MESO_OK;
}

void mesoi_fit_state_free(mesoi_fit_state* f)
{
    void* p[] = {f->keep, f->fixed, f->nosplit, f->seg_child, f->sparent, f->x, f->kstart, f->kids, f->owner, f->vseg,
                 f->verr, f->vnear, f->segerr, f->var, f->path, f->md.p, f->H, f->E, f->g, f->dx, f->r, f->z,
                 f->d, f->q, f->xt, f->segs, f->kappa, f->L};
    for (size_t i = 0; i < sizeof(p) / sizeof(p[0]); ++i)
        free(p[i]);
    memset(f, 0, sizeof(*f));
}
