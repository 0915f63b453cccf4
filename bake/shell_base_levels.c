/*
 * shell_base_levels.c — coarser base meshes of a shell with their directors
 * (shell_base_levels.h; issue 14: "coarser base meshes with their
 * directors (simplification from a well-kept library)"). A shell level
 * between the texture levels and the mesh stand-in: the same texture
 * function ray cast through fewer, larger prisms, which is what a shell a
 * few sizes away needs (its hull rasterising, not its march, is what costs:
 * bench_lod_scene's nearest shell spends ~40 of its 73 ms at 1 px on the
 * entry faces of 5856 prisms).
 *
 * The mapping. A shell draws Φ(T), T the texture function's surface in
 * texture space (u, v, w) and Φ the prisms' mapping (smooth-shells
 * sec. 3.1, shell_common.glsl `phi`): over a base triangle, with (u, v)
 * giving barycentrics b, Φ(u, v, w) = Σ b_i (bottom_i + w span_i). For
 * fixed w that is piecewise linear in (u, v) over the uv triangulation, and
 * for fixed (u, v) linear in w. A coarser base mesh whose uv triangulation
 * covers the same texture space gives another such Φ_c, and Φ_c(T) lies
 * within D = max |Φ_c − Φ| of Φ(T) both ways (each point moves by at most
 * D, whatever T is: height field, volume, animated). Φ_c − Φ is linear on
 * every cell of the two triangulations' overlay for fixed w and linear in
 * w, so |Φ_c − Φ|, convex on each cell, peaks at a vertex of the overlay at
 * w = 0 or 1: D is computed exactly (mesoi_shell_map_distance: every fine
 * triangle clipped by every coarse triangle of its chart it meets, the
 * clipped polygon's corners evaluated in double), not sampled. The caller
 * adds the texture level's own error (the triangle inequality).
 *
 * What the paper leaves open, decided here:
 * - The coarse levels keep level 0's vertices, with their directors and
 *   thickness, as a subset (meshopt_simplify, Debian's 0.18: each level
 *   half the triangles of the one before, simplified from the base so
 *   that what one level locked every later one keeps; a level keeping more
 *   than 85 % ends the chain, none from 256 triangles or fewer, as
 *   mesh_levels.c). Directors traced anew on the coarse mesh (the Lp field
 *   of sec. 4) would move every vertex's top as well; kept, a kept vertex's
 *   prism corners do not move, and D measures what the interpolation
 *   between them changes.
 * - Texture space stays as it is: uv seams and borders stay, and so do
 *   folds (vertices between triangles of both uv orientations: spot_uv has
 *   177 of 5856 triangles the other way round). Texture space is cut into
 *   regions, one orientation of one chart each, and only triangles of one
 *   region are compared. meshopt_SimplifyLockBorder keeps borders; 0.18
 *   pairs the two copies of a seam vertex by position and collapses along
 *   the seam, so each copy's position is nudged by a few float ulps for the
 *   simplifier alone, which makes the seam a border. 0.18 has no per-vertex
 *   lock, but it locks a position that three or more vertices of the
 *   buffer share, used or not: a locked vertex gets two unused copies.
 * - A level is kept only if it is as sound as level 0: every triangle
 *   within one region, its way round, with uv area (a region stays a
 *   triangulation of itself), and every prism's Jacobian proven positive
 *   (shell_validate.h; level 0 must pass too). meshopt knows neither, so
 *   where a triangle fails, the vertices the level removed around its
 *   corners (one of them collapsed into a corner) are locked and the level
 *   is simplified again, up to FOLD_RETRIES times (spot_uv at 10 %
 *   thickness took 29 tries). A level whose sound triangles alone already slide the texture
 *   farther than the stand-in's error ends the chain without retries.
 *   Faces left twice keep one (mesh_levels.c); a reversed pair is a fold.
 * - The bound covers the smooth (and segment and slices) mapping, Φ above.
 *   Curved shells (Coons patches) and tetra shells (Φ linear per tetrahedron)
 *   map differently: the runtime does not draw these levels for them
 *   (rt_levels.c `usable`).
 */
#include "shell_base_levels.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#if MESO_HAVE_MESHOPTIMIZER
#include <meshoptimizer.h>
#endif

#include "box_grid.h"
#include "mesh_levels.h"
#include "shell_validate.h"

void mesoi_shell_base_levels_free(mesoi_shell_base_level* levels, uint32_t count)
{
    for (uint32_t i = 0; levels && i < count; ++i) {
        meso_mesh_free(&levels[i].mesh);
        free(levels[i].sdir);
        free(levels[i].thick);
    }
    free(levels);
}

/* Twice the signed uv area of triangle t. */
static double uv_area2(const float* uv, const uint32_t* ix)
{
    const double ax = uv[2 * ix[0]], ay = uv[2 * ix[0] + 1];
    return ((double)uv[2 * ix[1]] - ax) * ((double)uv[2 * ix[2] + 1] - ay) -
           ((double)uv[2 * ix[2]] - ax) * ((double)uv[2 * ix[1] + 1] - ay);
}

/* >>distance ---------------------------------------------------------------- */

typedef struct tri_uv {
    double p[3][2]; /* counter-clockwise */
    int flip;       /* corners 1 and 2 swapped to make it so */
} tri_uv;

static tri_uv tri_of(const meso_mesh* m, uint32_t t)
{
    tri_uv r;
    const uint32_t* ix = m->indices + 3 * (size_t)t;
    for (int c = 0; c < 3; ++c) {
        r.p[c][0] = m->uvs[2 * ix[c]];
        r.p[c][1] = m->uvs[2 * ix[c] + 1];
    }
    r.flip = uv_area2(m->uvs, ix) < 0.0;
    if (r.flip)
        for (int k = 0; k < 2; ++k) {
            const double s = r.p[1][k];
            r.p[1][k] = r.p[2][k];
            r.p[2][k] = s;
        }
    return r;
}

/* Barycentrics of q in t, in the mesh's corner order. */
static void bary(const tri_uv* t, const double q[2], double b[3])
{
    const double e1x = t->p[1][0] - t->p[0][0], e1y = t->p[1][1] - t->p[0][1];
    const double e2x = t->p[2][0] - t->p[0][0], e2y = t->p[2][1] - t->p[0][1];
    const double qx = q[0] - t->p[0][0], qy = q[1] - t->p[0][1];
    const double d = e1x * e2y - e2x * e1y;
    const double b1 = (qx * e2y - e2x * qy) / d, b2 = (e1x * qy - qx * e1y) / d;
    b[0] = 1.0 - b1 - b2;
    b[1] = t->flip ? b2 : b1;
    b[2] = t->flip ? b1 : b2;
}

/* Φ(q, w) for w = 0 and 1 over triangle t of m: out[0..2] the bottom point,
 * out[3..5] the top. */
static void phi(const meso_mesh* m, const float* bottom, const float* span, uint32_t t, const double b[3],
                double out[6])
{
    memset(out, 0, 6 * sizeof(double));
    for (int c = 0; c < 3; ++c) {
        const uint32_t v = m->indices[3 * (size_t)t + (size_t)c];
        for (int k = 0; k < 3; ++k) {
            out[k] += b[c] * bottom[3 * (size_t)v + (size_t)k];
            out[3 + k] += b[c] * ((double)bottom[3 * (size_t)v + (size_t)k] + span[3 * (size_t)v + (size_t)k]);
        }
    }
}

/* Clips the convex polygon poly[0..n) (counter-clockwise) by the half-plane
 * left of a -> b; returns the new count (at most n + 1). */
static int clip(double poly[][2], int n, const double a[2], const double b[2])
{
    double out[12][2];
    int m = 0;
    const double ex = b[0] - a[0], ey = b[1] - a[1];
    for (int i = 0; i < n; ++i) {
        const double* p = poly[i];
        const double* q = poly[(i + 1) % n];
        const double sp = ex * (p[1] - a[1]) - ey * (p[0] - a[0]);
        const double sq = ex * (q[1] - a[1]) - ey * (q[0] - a[0]);
        if (sp >= 0.0 && m < 12) {
            out[m][0] = p[0];
            out[m++][1] = p[1];
        }
        if ((sp >= 0.0) != (sq >= 0.0) && m < 12) {
            const double t = sp / (sp - sq);
            out[m][0] = p[0] + t * (q[0] - p[0]);
            out[m++][1] = p[1] + t * (q[1] - p[1]);
        }
    }
    memcpy(poly, out, sizeof(double) * 2 * (size_t)m);
    return m;
}

/* The uv box of triangle t, z 0 (box_grid.h is 3D). */
static void uv_box(const tri_uv* t, double lo[3], double hi[3])
{
    for (int k = 0; k < 2; ++k) {
        lo[k] = fmin(fmin(t->p[0][k], t->p[1][k]), t->p[2][k]);
        hi[k] = fmax(fmax(t->p[0][k], t->p[1][k]), t->p[2][k]);
    }
    lo[2] = hi[2] = 0.0;
}

double mesoi_shell_map_distance(const meso_mesh* fine, const float* fine_bottom, const float* fine_span,
                                const uint32_t* chart, const meso_mesh* coarse, const float* coarse_bottom,
                                const float* coarse_span, const uint32_t* coarse_chart)
{
    const uint32_t nc = coarse->triangle_count;
    /* The coarse triangles' uv boxes in a grid of cells about their mean size. */
    double lo[3], hi[3], extent = 0.0;
    for (uint32_t t = 0; t < nc; ++t) {
        const tri_uv c = tri_of(coarse, t);
        uv_box(&c, lo, hi);
        extent += fmax(hi[0] - lo[0], hi[1] - lo[1]);
    }
    meso_box_grid* g = meso_box_grid_create(nc, nc && extent > 0.0 ? extent / nc : 1.0);
    int ok = g != NULL;
    for (uint32_t t = 0; ok && t < nc; ++t) {
        const tri_uv c = tri_of(coarse, t);
        uv_box(&c, lo, hi);
        ok = meso_box_grid_set(g, t, lo, hi);
    }
    uint32_t* near = NULL;
    size_t cap = 0;
    double result = 0.0;
    for (uint32_t f = 0; ok && f < fine->triangle_count; ++f) {
        const tri_uv F = tri_of(fine, f);
        uv_box(&F, lo, hi);
        size_t n = 0;
        ok = meso_box_grid_query(g, lo, hi, &near, &n, &cap);
        for (size_t i = 0; ok && i < n; ++i) {
            const uint32_t t = near[i];
            if (coarse_chart[t] != chart[f])
                continue;
            const tri_uv C = tri_of(coarse, t);
            double poly[12][2];
            memcpy(poly, F.p, sizeof F.p);
            int m = 3;
            for (int e = 0; e < 3 && m > 0; ++e)
                m = clip(poly, m, C.p[e], C.p[(e + 1) % 3]);
            for (int j = 0; j < m; ++j) {
                double bf[3], bc[3], pf[6], pc[6];
                bary(&F, poly[j], bf);
                bary(&C, poly[j], bc);
                phi(fine, fine_bottom, fine_span, f, bf, pf);
                phi(coarse, coarse_bottom, coarse_span, t, bc, pc);
                for (int w = 0; w < 2; ++w) {
                    const double dx = pf[3 * w] - pc[3 * w], dy = pf[3 * w + 1] - pc[3 * w + 1],
                                 dz = pf[3 * w + 2] - pc[3 * w + 2];
                    result = fmax(result, sqrt(dx * dx + dy * dy + dz * dz));
                }
            }
        }
    }
    free(near);
    meso_box_grid_destroy(g);
    return ok ? result : -1.0;
}

/* >>chain ------------------------------------------------------------------- */

#if MESO_HAVE_MESHOPTIMIZER

static uint32_t find(uint32_t* parent, uint32_t v)
{
    while (parent[v] != v)
        v = parent[v] = parent[parent[v]];
    return v;
}

/* Bottoms and spans (top − bottom) of m's vertices from its directors
 * (fill_vertex_texels in rt_shell.c). */
static void bottom_span(const float* pos, const float* sdir, int layers, uint32_t nv, float* bottom, float* span)
{
    for (size_t i = 0; i < 3 * (size_t)nv; ++i) {
        const float b = layers == 2 ? pos[i] + sdir[3 * (size_t)nv + i] : pos[i];
        bottom[i] = b;
        span[i] = pos[i] + sdir[i] - b;
    }
}

/* Prisms not proven valid (shell_validate.h) over `m` with these bottoms and
 * spans; UINT32_MAX on failure. */
static uint32_t inverted(const meso_mesh* m, const float* bottom, const float* span)
{
    meso_mesh b = *m;
    b.positions = (float*)bottom;
    uint32_t n = 0;
    meso_error e;
    return meso_shell_count_inverted(&b, span, 1, NULL, &n, NULL, &e) == MESO_OK ? n : UINT32_MAX;
}

typedef struct chain {
    const mesoi_shell_base_levels_input* in;
    /* Regions: node 2 v + (s > 0) is vertex v within the base triangles of
     * uv orientation s; a triangle joins its corners' nodes. A region is
     * one orientation of one chart (a mirrored piece, or the far side of a
     * fold, is a region of its own). */
    uint32_t* node;    /* [2 nv]: union-find parent, UINT32_MAX where no triangle of that orientation is */
    uint32_t* region;  /* [nt]: each base triangle's region */
    uint32_t *vt_start, *vt_list; /* the base triangles around each vertex */
    uint8_t* locked;   /* [nv]: the vertex stays (a fold's, or one whose collapse folded the uvs) */
    uint32_t* sidx;    /* the base triangles for the simplifier, in its vertex ids */
    float* spos;       /* [3 (3 nv)]: the simplifier's positions */
    uint32_t sv;       /* simplifier vertices */
    float *bottom, *span;
    double min_area2;  /* a coarse triangle's uv area (doubled) must exceed this */
} chain;

static int sign_of(double a)
{
    return a > 0.0 ? 1 : 0;
}

/* Regions, the triangles around each vertex, and the fold vertices
 * locked; *why when the base does not allow coarse levels. */
static meso_result chain_begin(chain* c, const char** why)
{
    const meso_mesh* m = c->in->base;
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    const size_t ni = 3 * (size_t)nt;
    c->node = malloc(sizeof(uint32_t) * 2 * (size_t)nv);
    c->region = malloc(sizeof(uint32_t) * (nt ? nt : 1));
    c->vt_start = calloc((size_t)nv + 1, sizeof(uint32_t));
    c->vt_list = malloc(sizeof(uint32_t) * (ni ? ni : 1));
    c->locked = calloc(nv, 1);
    c->sidx = malloc(sizeof(uint32_t) * (ni ? ni : 1));
    c->spos = calloc(9 * (size_t)nv, sizeof(float));
    c->bottom = malloc(sizeof(float) * 3 * nv);
    c->span = malloc(sizeof(float) * 3 * nv);
    if (!c->node || !c->region || !c->vt_start || !c->vt_list || !c->locked || !c->sidx || !c->spos ||
        !c->bottom || !c->span)
        return MESO_ERR_OUT_OF_MEMORY;
    for (size_t i = 0; i < 2 * (size_t)nv; ++i)
        c->node[i] = UINT32_MAX;
    double max_area2 = 0.0;
    for (uint32_t t = 0; t < nt && !*why; ++t) {
        const uint32_t* ix = m->indices + 3 * (size_t)t;
        const double a = uv_area2(m->uvs, ix);
        const uint32_t s = (uint32_t)sign_of(a);
        max_area2 = fmax(max_area2, fabs(a));
        if (a == 0.0)
            *why = "a triangle's texture coordinates have no area";
        for (int k = 0; k < 3; ++k)
            if (c->node[2 * ix[k] + s] == UINT32_MAX)
                c->node[2 * ix[k] + s] = 2 * ix[k] + s;
        for (int k = 1; k < 3; ++k) {
            const uint32_t a0 = find(c->node, 2 * ix[0] + s), ak = find(c->node, 2 * ix[k] + s);
            c->node[ak > a0 ? ak : a0] = ak > a0 ? a0 : ak;
        }
    }
    if (*why)
        return MESO_OK;
    c->min_area2 = 1e-9 * max_area2;
    for (size_t i = 0; i < ni; ++i)
        ++c->vt_start[m->indices[i] + 1];
    for (uint32_t v = 0; v < nv; ++v)
        c->vt_start[v + 1] += c->vt_start[v];
    for (uint32_t t = 0; t < nt; ++t) {
        const uint32_t* ix = m->indices + 3 * (size_t)t;
        c->region[t] = find(c->node, 2 * ix[0] + (uint32_t)sign_of(uv_area2(m->uvs, ix)));
        for (int k = 0; k < 3; ++k)
            c->vt_list[c->vt_start[ix[k]]++] = t;
    }
    for (uint32_t v = nv; v > 0; --v) /* vt_start[v] ran on to vt_start[v + 1] */
        c->vt_start[v] = c->vt_start[v - 1];
    c->vt_start[0] = 0;
    for (uint32_t v = 0; v < nv; ++v)
        c->locked[v] = c->node[2 * v] != UINT32_MAX && c->node[2 * v + 1] != UINT32_MAX;
    bottom_span(m->positions, c->in->sdir, c->in->layers, nv, c->bottom, c->span);
    if (inverted(m, c->bottom, c->span) != 0)
        *why = "level 0 has prisms not proven valid";
    return MESO_OK;
}

/* The simplifier's input for the locked vertices. 0.18 has no per-vertex
 * lock, but it locks a vertex whose position three or more vertices of
 * the buffer share, used or not (mesh_levels.c found that the hard way),
 * so each locked vertex gets two unused copies. Seam vertices must stay
 * too, and 0.18 pairs two copies of one position as a seam and collapses
 * along it: the k-th copy of a position moves k ulps in x first, which
 * makes the seam a border, and meshopt_SimplifyLockBorder keeps borders. */
static meso_result simplifier_input(chain* c)
{
    const meso_mesh* m = c->in->base;
    const uint32_t nv = m->vertex_count;
    memcpy(c->sidx, m->indices, sizeof(uint32_t) * 3 * (size_t)m->triangle_count);
    memcpy(c->spos, m->positions, sizeof(float) * 3 * (size_t)nv);
    uint32_t* remap = calloc(nv, sizeof(uint32_t));
    uint32_t* copies = calloc(nv, sizeof(uint32_t));
    if (!remap || !copies) {
        free(remap);
        free(copies);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    meshopt_generateVertexRemap(remap, NULL, nv, c->spos, nv, 3 * sizeof(float));
    for (uint32_t v = 0; v < nv; ++v)
        for (uint32_t k = copies[remap[v]]++; k > 0; --k)
            c->spos[3 * (size_t)v] = nextafterf(c->spos[3 * (size_t)v], INFINITY);
    free(remap);
    free(copies);
    c->sv = nv;
    for (uint32_t v = 0; v < nv; ++v)
        if (c->locked[v])
            for (int k = 0; k < 2; ++k)
                memcpy(c->spos + 3 * (size_t)c->sv++, c->spos + 3 * (size_t)v, 3 * sizeof(float));
    return MESO_OK;
}

static void chain_end(chain* c)
{
    free(c->node);
    free(c->region);
    free(c->vt_start);
    free(c->vt_list);
    free(c->locked);
    free(c->sidx);
    free(c->spos);
    free(c->bottom);
    free(c->span);
}

/* Locks the base vertices around the corners of triangle ix (base
 * vertices) that `present` says a level removed: one of them collapsed
 * into a corner. Returns how many were newly locked. */
static uint32_t lock_around(chain* c, const uint32_t* ix, const uint8_t* present)
{
    const meso_mesh* m = c->in->base;
    uint32_t more = 0;
    for (int k = 0; k < 3; ++k)
        for (uint32_t i = c->vt_start[ix[k]]; i < c->vt_start[ix[k] + 1]; ++i)
            for (int j = 0; j < 3; ++j) {
                const uint32_t x = m->indices[3 * (size_t)c->vt_list[i] + (size_t)j];
                if (!present[x] && !c->locked[x]) {
                    c->locked[x] = 1;
                    ++more;
                }
            }
    return more;
}

/* The regions of the triangles idx[0..3 nt) (base vertices) into
 * region[]; flags in bad[] those in no one region the region's way round
 * (or with no uv area): their simplification folded the texture
 * coordinates. Returns how many. */
static uint32_t folds(const chain* c, const uint32_t* idx, uint32_t nt, uint32_t* region, uint8_t* bad)
{
    const meso_mesh* m = c->in->base;
    uint32_t n = 0;
    for (uint32_t t = 0; t < nt; ++t) {
        const uint32_t* ix = idx + 3 * (size_t)t;
        const double a = uv_area2(m->uvs, ix);
        const uint32_t s = (uint32_t)sign_of(a);
        uint32_t g[3];
        for (int k = 0; k < 3; ++k)
            g[k] = c->node[2 * ix[k] + s] == UINT32_MAX ? UINT32_MAX : find(c->node, 2 * ix[k] + s);
        region[t] = g[0];
        bad[t] = !(fabs(a) > c->min_area2 && g[0] != UINT32_MAX && g[0] == g[1] && g[0] == g[2]);
        n += bad[t];
    }
    return n;
}

/* Level `lv` from the base triangles idx[0..ni) in `region`s (UINT32_MAX:
 * left out of the distance), unless some of its prisms are not proven
 * valid (shell_validate.h; checked when `check` is set): then bad[] flags
 * them and *bad_count says how many. */
static meso_result make_level(const chain* c, const uint32_t* idx, size_t ni, const uint32_t* region,
                              mesoi_shell_base_level* lv, uint8_t* bad, uint32_t* bad_count, int check)
{
    const mesoi_shell_base_levels_input* in = c->in;
    const meso_mesh* m = in->base;
    const uint32_t nv = m->vertex_count, nt = (uint32_t)(ni / 3);
    meso_result r = meso_mesh_subset(m, idx, nt, &lv->mesh);
    const uint32_t n = lv->mesh.vertex_count, L = (uint32_t)in->layers;
    uint8_t* used = calloc(nv, 1);
    float* bottom = malloc(sizeof(float) * 3 * (n ? n : 1));
    float* span = malloc(sizeof(float) * 3 * (n ? n : 1));
    lv->sdir = malloc(sizeof(float) * 3 * (n ? n : 1) * L);
    lv->thick = malloc(sizeof(float) * (n ? n : 1));
    if (r == MESO_OK && (!used || !bottom || !span || !lv->sdir || !lv->thick))
        r = MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_OK) {
        /* meso_mesh_subset keeps the used vertices in the base's order. */
        for (size_t k = 0; k < ni; ++k)
            used[idx[k]] = 1;
        uint32_t d = 0;
        for (uint32_t v = 0; v < nv; ++v)
            if (used[v]) {
                for (uint32_t l = 0; l < L; ++l)
                    memcpy(lv->sdir + 3 * ((size_t)l * n + d), in->sdir + 3 * ((size_t)l * nv + v),
                           3 * sizeof(float));
                lv->thick[d] = in->thick[v];
                memcpy(bottom + 3 * (size_t)d, c->bottom + 3 * (size_t)v, 3 * sizeof(float));
                memcpy(span + 3 * (size_t)d, c->span + 3 * (size_t)v, 3 * sizeof(float));
                ++d;
            }
        meso_mesh b = lv->mesh;
        b.positions = bottom;
        meso_error e;
        *bad_count = 0;
        if (check && meso_shell_count_inverted(&b, span, 1, bad, bad_count, NULL, &e) != MESO_OK) {
            r = MESO_ERR_OUT_OF_MEMORY; /* the arrays are ours: nothing else fails */
        } else if (*bad_count == 0) {
            lv->distance =
                mesoi_shell_map_distance(m, c->bottom, c->span, c->region, &lv->mesh, bottom, span, region);
            if (lv->distance < 0.0)
                r = MESO_ERR_OUT_OF_MEMORY;
        }
    }
    free(used);
    free(bottom);
    free(span);
    return r;
}

/* Retries of one level after locking what folded the uvs. */
enum { FOLD_RETRIES = 64 };

meso_result mesoi_shell_base_levels_build(const mesoi_shell_base_levels_input* in, mesoi_shell_base_level** levels,
                                          uint32_t* count, const char** why, double* too_far, meso_error* err)
{
    *levels = NULL;
    *count = 0;
    *why = NULL;
    *too_far = -1.0;
    const meso_mesh* m = in->base;
    const uint32_t max = in->max_levels < MESOI_SHELL_BASE_LEVELS_MAX ? in->max_levels : MESOI_SHELL_BASE_LEVELS_MAX;
    if (max == 0)
        return MESO_OK;
    if (!m->uvs) {
        *why = "the base mesh has no texture coordinates";
        return MESO_OK;
    }
    chain c = {.in = in};
    const uint32_t nt = m->triangle_count;
    const size_t ni = 3 * (size_t)nt;
    mesoi_shell_base_level* out = calloc(max, sizeof(*out));
    uint32_t* next = malloc(sizeof(uint32_t) * (ni ? ni : 1));
    uint32_t* idx = malloc(sizeof(uint32_t) * (ni ? ni : 1));
    uint32_t* region = malloc(sizeof(uint32_t) * (nt ? nt : 1));
    uint8_t* flag = malloc(2 * (size_t)nt + 1);
    uint32_t* early = malloc(sizeof(uint32_t) * (nt ? nt : 1));
    uint8_t* present = malloc(m->vertex_count ? m->vertex_count : 1);
    meso_result r = out && next && idx && region && flag && early && present ? chain_begin(&c, why) : MESO_ERR_OUT_OF_MEMORY;
    uint32_t made = 0, prev = nt;
    /* Each level from the base mesh (so that what one level locked, every
     * level after it keeps locked), with half the triangles of the one
     * before. */
    while (r == MESO_OK && !*why && made < max && prev > MESO_MESH_LEVELS_MIN_TRIANGLES) {
        const size_t target = 3 * (size_t)(prev / 2);
        size_t got = 0;
        uint32_t bad = 1;
        mesoi_shell_base_level lv = {0};
        for (int attempt = 0; r == MESO_OK && bad && attempt <= FOLD_RETRIES; ++attempt) {
            meso_mesh_free(&lv.mesh);
            free(lv.sdir);
            free(lv.thick);
            memset(&lv, 0, sizeof lv);
            *why = NULL;
            if ((r = simplifier_input(&c)) != MESO_OK)
                break;
            got = meshopt_simplify(next, c.sidx, ni, c.spos, c.sv, 3 * sizeof(float), target, 1.0f,
                                   meshopt_SimplifyLockBorder, NULL);
            if ((double)got > 0.85 * 3.0 * prev || got == 0)
                break; /* what is left will not halve: seams, borders and locks hold it */
            got = mesoi_drop_duplicate_faces(next, got); /* a reversed pair is a fold below */
            if (got == SIZE_MAX) {
                r = MESO_ERR_OUT_OF_MEMORY;
                break;
            }
            const uint32_t gt = (uint32_t)(got / 3);
            memcpy(idx, next, sizeof(uint32_t) * got);
            bad = folds(&c, idx, gt, region, flag);
            *why = bad ? "a collapse would fold the texture coordinates" : NULL;
            if (!bad) {
                r = make_level(&c, idx, got, region, &lv, flag, &bad, 1);
                *why = bad ? "a coarse prism is not proven valid" : NULL;
            } else if (attempt == 0) {
                /* Not worth the retries when the sound triangles already
                 * slide the texture too far: the retries only lock more. */
                for (uint32_t t = 0; t < gt; ++t)
                    early[t] = flag[t] ? UINT32_MAX : region[t];
                uint32_t none = 0;
                mesoi_shell_base_level probe = {0};
                r = make_level(&c, idx, got, early, &probe, flag + gt, &none, 0);
                const double d = probe.distance;
                meso_mesh_free(&probe.mesh);
                free(probe.sdir);
                free(probe.thick);
                if (r == MESO_OK && !(d < in->limit)) {
                    *why = "its distance to level 0 is not below the stand-in's error";
                    *too_far = d;
                    break;
                }
            }
            /* Lock what collapsed into a bad triangle's corners; again. */
            memset(present, 0, m->vertex_count);
            for (size_t k = 0; k < got; ++k)
                present[idx[k]] = 1;
            uint32_t more = 0;
            for (uint32_t t = 0; r == MESO_OK && bad && t < gt; ++t)
                if (flag[t])
                    more += lock_around(&c, idx + 3 * (size_t)t, present);
            if (bad && !more)
                break;
        }
        if (r == MESO_OK && !*why && !bad && got && (double)got <= 0.85 * 3.0 * prev && !(lv.distance < in->limit)) {
            *why = "its distance to level 0 is not below the stand-in's error";
            *too_far = lv.distance;
        }
        if (r != MESO_OK || *why || bad || (double)got > 0.85 * 3.0 * prev || got == 0) {
            meso_mesh_free(&lv.mesh);
            free(lv.sdir);
            free(lv.thick);
            break;
        }
        out[made++] = lv;
        prev = (uint32_t)(got / 3);
    }
    chain_end(&c);
    free(next);
    free(idx);
    free(region);
    free(flag);
    free(early);
    free(present);
    if (r != MESO_OK) {
        mesoi_shell_base_levels_free(out, made);
        return meso_bake_fail(err, r, 0, "shell base levels: out of memory");
    }
    *levels = out;
    *count = made;
    return MESO_OK;
}

#else /* !MESO_HAVE_MESHOPTIMIZER */

meso_result mesoi_shell_base_levels_build(const mesoi_shell_base_levels_input* in, mesoi_shell_base_level** levels,
                                          uint32_t* count, const char** why, double* too_far, meso_error* err)
{
    (void)in;
    (void)err;
    *too_far = -1.0;
    *levels = NULL;
    *count = 0;
    *why = "built without meshoptimizer";
    return MESO_OK;
}

#endif
