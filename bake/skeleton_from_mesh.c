/*
 * skeleton_from_mesh.c — closed mesh -> skeleton with radii, simplified to a
 * tolerance. The decisions are in skeleton_from_mesh.h; this file holds the
 * public distances, the output and the pipeline, and the stages live in
 * files named after them (skeleton_from_mesh_internal.h lists them).
 *
 * Stages (greppable banners): >>geometry (the public distances), >>output,
 * >>main.
 */
#include "skeleton_from_mesh.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "meso_clock.h"
#include "skeleton_from_mesh_internal.h"

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

/* >>output -------------------------------------------------------------- */

/* Kept nodes in depth-first preorder from each root (children by index). */
static meso_result make_output(const mesoi_fit_state* f, meso_skeleton* out, meso_error* err)
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
    out->node_count = nk;
    meso_skeleton_group_children(out, index);
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

/* CGAL, then the tree with per-node radii (skeleton_tree.c). */
static meso_result skeleton_tree(const mesoi_clean_mesh* c, double medial_weight, mesoi_work_tree* w,
                                 meso_skeleton_fit_stats* st, meso_error* err)
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
    r = mesoi_work_tree_from_cgal(c, &cs, w, err);
    cgal_skeleton_free(&cs);
    st->cgal_nodes = w->ncgal;
    st->cgal_edges = w->edges;
    st->cycles_broken = w->cycles;
    st->unmapped_vertices = w->unmapped;
    return r;
}

/* Fit error of CGAL's tree with the per-node radii (before anything else). */
static meso_result cgal_tree_error(const mesoi_clean_mesh* c, const mesoi_work_tree* w, meso_skeleton_fit_stats* st,
                                   meso_error* err)
{
    mesoi_model md;
    double* x = malloc(sizeof(double) * 4 * (w->n ? w->n : 1));
    meso_result r = mesoi_model_alloc(w->n, &md, err);
    if (r == MESO_OK && !x)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "skeleton from mesh: out of memory");
    if (r == MESO_OK) {
        for (uint32_t i = 0; i < w->n; ++i) {
            memcpy(x + 4 * (size_t)i, w->pos + 3 * (size_t)i, sizeof(double) * 3);
            x[4 * (size_t)i + 3] = w->rad[i];
        }
        mesoi_model_fill(x, w->parent, NULL, w->n, &md);
        mesoi_mesh_to_model(c, &md, &st->cgal_fit_error_max, &st->cgal_fit_error_mean);
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
    (void)t0;
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0, "skeleton from mesh: this build has no CGAL");
#else
    mesoi_clean_mesh c;
    meso_result r = mesoi_skel_check_and_clean(mesh, &c, err);
    if (r != MESO_OK)
        return r;
    st.mesh_vertices = c.nv;
    st.mesh_triangles = c.nt;
    st.flipped = (uint32_t)c.flipped;
    st.bbox_diagonal = c.diag;
    st.tolerance = o.tolerance > 0 && isfinite(o.tolerance) ? o.tolerance : MESO_SKELFIT_DEFAULT_TOLERANCE * c.diag;

    mesoi_work_tree w;
    memset(&w, 0, sizeof(w));
    mesoi_fit_state f;
    memset(&f, 0, sizeof(f));
    r = skeleton_tree(&c, o.medial_weight > 0 ? o.medial_weight : MESO_SKELFIT_DEFAULT_MEDIAL_WEIGHT, &w, &st, err);
    if (r == MESO_OK)
        r = cgal_tree_error(&c, &w, &st, err);
    if (r == MESO_OK)
        r = mesoi_fit_state_init(&f, &c, &w, st.tolerance, o.fit == MESO_SKELFIT_LSQ && !o.no_simplify, o.no_simplify,
                           err);
    if (r == MESO_OK)
        r = mesoi_fit_skeleton(&f, !o.no_simplify, err);
    if (r == MESO_OK)
        r = make_output(&f, out, err);
    if (r == MESO_OK) {
        mesoi_mesh_to_model(&c, &f.md, &st.fit_error_max, &st.fit_error_mean);
        r = mesoi_model_to_mesh(&c, &f.md, mesoi_sample_spacing(&f.md, st.tolerance), &st.model_to_mesh_max,
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
    mesoi_fit_state_free(&f);
    mesoi_work_tree_free(&w);
    mesoi_clean_mesh_free(&c);
    st.seconds_total = meso_seconds() - t0;
    if (stats)
        *stats = st;
    return r;
#endif
}
