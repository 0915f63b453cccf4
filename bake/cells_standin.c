/*
 * cells_standin.c — how far a stand-in mesh is from what a cells object
 * draws (cells_standin.h; FORMAT.md §7.10 `error`, issue 14).
 *
 * The surface a cells object draws. FORMAT.md §7.2 kind 3 and
 * runtime/reference/cell_reference.h: the solid is the union of the closed
 * voxel cubes whose split cell is tagged INSIDE; its surface is the set of
 * voxel faces between a SOLID voxel and a non-SOLID one (beyond the grid
 * counts as non-SOLID). Those faces are collected here as a triangle soup
 * (two triangles per face, none merged: surface_distance.c samples a
 * triangle n x n times along its longest edge, so long merged faces would
 * cost more samples, not fewer). Carving is in it: an INTERSECTED cell is
 * empty, so the faces of the INSIDE cells next to it lie as deep under the
 * mesh as that cell reaches.
 *
 * The measurement, each way an upper bound (distances to a surface are
 * 1-Lipschitz):
 *  - cells -> stand-in: d_A = the largest distance from a face's centre to
 *    the stand-in (exact queries over triangle_grid.c), + h / sqrt(2), the
 *    farthest a point of the face is from its centre;
 *  - stand-in -> cells: d_B = the largest distance from samples of the
 *    stand-in to the face soup, sampled as surface_distance.c samples
 *    (each triangle cut into n x n similar ones, n = ceil(longest edge /
 *    spacing), spacing 1.001 sqrt(2) h), + its sampling radius r (the
 *    largest sub-triangle edge / sqrt(3); surface_distance.h says why).
 * Both maxima skip points that cannot raise them (>>sampled maxima): a
 * point far inside a carved region is far from every face, and a query
 * there visits many grid cells, so querying every sample cost 20 times
 * the bake on spot at 256 voxels across.
 *
 * Decided here where the format leaves room. libmeso's rays start where
 * they enter the base mesh (§3.2.1 of the thesis), so what it draws is the
 * solid clipped to the mesh, not the reference's unclipped solid. A drawn
 * voxel's centre is inside the mesh, its cube reaches at most h sqrt(3) / 2
 * beyond. The clipped surface is made of points of the solid's surface
 * inside the mesh (a subset of the faces: d_A covers them) and of the mesh
 * inside the solid (on the base mesh: distance 0 to a base-mesh stand-in).
 * The other way, a stand-in point p within d of a face point q: if q is
 * outside the mesh, the segment from q to its voxel's centre (inside)
 * crosses the mesh at x inside the solid, on the clipped surface, with
 * |q - x| <= h sqrt(3) / 2. So
 *
 *     bound = max(d_A + h / sqrt(2), d_B + r) + h sqrt(3) / 2
 *
 * (the clipping term on both sides: simpler, and at most 0.87 h loose),
 * then a margin of 8 f32 ulps of the largest coordinate (the faces' corners
 * are f32 values of origin + index h), and it holds for the reference's
 * solid and for the clipped one alike (with --voxelizer winding on an open
 * mesh "inside" is winding >= 1/2 and the crossing argument is not exact).
 * For a coarser stand-in S' of the base mesh B the bake adds B's measured
 * distance to S' (mesh_levels.c): Hausdorff distances obey the triangle
 * inequality.
 *
 * At most MESO_CELLS_STANDIN_MAX_FACES faces are measured (a bigger
 * surface gets no bound, and the bake no stand-in): the demo's torus of
 * sphere cells at 768 voxels across has 4.4 M faces and took 40 s and
 * 860 MB this way, against 0.8 s for the bake without levels.
 * Cost: one pass over the voxels of the tiles that are not OUTSIDE (six
 * neighbour tests per SOLID voxel), 72 bytes per face for the soup, 96 for
 * its f64 copy and the triangle grid over it; the queries run on OpenMP.
 * Deterministic: faces are listed in voxel order, and the maxima and the
 * points queried do not depend on the thread count.
 */
#include "cells_standin.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"
#include "srgb.h"
#include "triangle_grid.h"

typedef struct soup {
    float* xyz;
    uint32_t* tri;
    uint32_t* vox; /* per face: its solid voxel's index within the tile, x + R (y + R z) (the COLR texel) */
    uint64_t faces, cap;
    int count_only; /* 1: add_face counts */
} soup;

static int solid(const meso_voxel_grid* g, const meso_split_cells* sc, const meso_membership* mb, int64_t i, int64_t j,
                 int64_t k)
{
    const int64_t R = g->tile_res;
    if (i < 0 || j < 0 || k < 0 || i >= (int64_t)g->tiles[0] * R || j >= (int64_t)g->tiles[1] * R ||
        k >= (int64_t)g->tiles[2] * R)
        return 0;
    const uint32_t s = sc->voxel_split[(i % R) + R * ((j % R) + R * (k % R))];
    return s && meso_membership_get(mb, (uint32_t)(i / R), (uint32_t)(j / R), (uint32_t)(k / R), s) ==
                    MESO_MEMB_INSIDE;
}

/* The face of voxel (i, j, k) on side `dir` (axis dir / 2, + when odd). */
static int add_face(soup* s, const meso_voxel_grid* g, int64_t i, int64_t j, int64_t k, int dir)
{
    if (s->count_only) {
        ++s->faces;
        return 1;
    }
    if (s->faces == s->cap) {
        const uint64_t cap = s->cap ? 2 * s->cap : 4096;
        if (cap > (UINT32_MAX / 4))
            return 0;
        float* x = realloc(s->xyz, sizeof(float) * 12 * cap);
        if (x)
            s->xyz = x;
        uint32_t* t = realloc(s->tri, sizeof(uint32_t) * 6 * cap);
        if (t)
            s->tri = t;
        uint32_t* o = realloc(s->vox, sizeof(uint32_t) * cap);
        if (o)
            s->vox = o;
        if (!x || !t || !o)
            return 0;
        s->cap = cap;
    }
    const int a = dir / 2, b = (a + 1) % 3, c = (a + 2) % 3;
    int64_t base[3] = {i, j, k};
    base[a] += dir & 1;
    static const int corner[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    float* x = s->xyz + 12 * s->faces;
    for (int q = 0; q < 4; ++q) {
        int64_t p[3] = {base[0], base[1], base[2]};
        p[b] += corner[q][0];
        p[c] += corner[q][1];
        for (int d = 0; d < 3; ++d)
            x[3 * q + d] = (float)(g->origin[d] + (double)p[d] * g->voxel_size);
    }
    const uint32_t v = (uint32_t)(4 * s->faces);
    uint32_t* t = s->tri + 6 * s->faces;
    const uint32_t idx[6] = {v, v + 1, v + 2, v, v + 2, v + 3};
    memcpy(t, idx, sizeof idx);
    const int64_t R = g->tile_res;
    s->vox[s->faces] = (uint32_t)((i % R) + R * ((j % R) + R * (k % R)));
    ++s->faces;
    return 1;
}

/* >>sampled maxima. The largest distance from a set of points, in blocks
 * of nearby points, to the surface of a triangle grid. Only the maximum is
 * wanted, so a point within W0 - d of the last point of its block queried
 * (which was d away) is skipped: distances to a surface are 1-Lipschitz, it
 * cannot exceed W0, a lower bound of the maximum taken first (the exact
 * distances of every block's first point). W0 and the points queried in a
 * block do not depend on the threads, so neither does the result. */
typedef struct sampler {
    uint64_t blocks;
    uint32_t (*count)(const void* u, uint64_t b);
    void (*point)(const void* u, uint64_t b, uint32_t i, double p[3]);
    const void* u;
} sampler;

static double sampled_max(const sampler* sm, const mesoi_tri_grid* g, int threads, int* failed)
{
    double w0 = 0, worst = 0;
    int bad = 0;
    const int nth = meso_bake_thread_count(threads);
    for (int pass = 0; pass < 2; ++pass) {
        double w = 0;
#ifdef _OPENMP
#pragma omp parallel num_threads(nth) reduction(max : w) reduction(| : bad)
#endif
        {
            mesoi_tri_grid mine = *g; /* shared cells, private stamps */
            mine.stamp = calloc(g->nt ? g->nt : 1, sizeof(uint32_t));
            mine.query = 0;
            bad |= !mine.stamp;
#ifdef _OPENMP
#pragma omp for schedule(dynamic, 16)
#endif
            for (int64_t b = 0; b < (int64_t)sm->blocks; ++b) {
                if (!mine.stamp)
                    continue;
                double p[3], last[3] = {0, 0, 0}, dlast = INFINITY;
                const uint32_t n = pass ? sm->count(sm->u, (uint64_t)b) : 1;
                for (uint32_t i = 0; i < n; ++i) {
                    sm->point(sm->u, (uint64_t)b, i, p);
                    const double step = sqrt((p[0] - last[0]) * (p[0] - last[0]) + (p[1] - last[1]) * (p[1] - last[1]) +
                                             (p[2] - last[2]) * (p[2] - last[2]));
                    if (dlast + step <= w0)
                        continue;
                    dlast = mesoi_tri_grid_distance(&mine, p);
                    memcpy(last, p, sizeof last);
                    w = dlast > w ? dlast : w;
                }
            }
            free(mine.stamp);
        }
        if (pass == 0)
            w0 = w;
        else
            worst = w;
    }
#ifndef _OPENMP
    (void)nth;
#endif
    *failed |= bad;
    return worst > w0 ? worst : w0;
}

enum { FACE_BLOCK = 64 };

/* Items in block b of n items cut into blocks of FACE_BLOCK. */
static uint32_t block_items(uint64_t n, uint64_t b)
{
    const uint64_t left = n - b * FACE_BLOCK;
    return left < FACE_BLOCK ? (uint32_t)left : FACE_BLOCK;
}

/* Cells -> stand-in: face centres, FACE_BLOCK consecutive faces a block. */
static uint32_t face_count(const void* u, uint64_t b)
{
    return block_items(((const soup*)u)->faces, b);
}

static void face_centre(const void* u, uint64_t b, uint32_t i, double c[3])
{
    const soup* s = u;
    const float* q = s->xyz + 12 * (b * FACE_BLOCK + i); /* corners 0 and 2 are opposite */
    for (int k = 0; k < 3; ++k)
        c[k] = 0.5 * ((double)q[k] + q[6 + k]);
}

/* Stand-in -> cells: each triangle subdivided into n x n similar ones,
 * n = ceil(longest edge / spacing), their corners (surface_distance.c's
 * samples); a triangle a block. */
typedef struct tri_samples {
    const meso_mesh* m;
    double spacing;
} tri_samples;

static const float* vtx(const meso_mesh* m, uint64_t t, int k)
{
    return m->positions + 3 * (size_t)m->indices[3 * t + (uint64_t)k];
}

static int subdivisions(const meso_mesh* m, uint64_t t, double spacing, double* longest)
{
    double l = 0;
    for (int k = 0; k < 3; ++k) {
        const float *p = vtx(m, t, k), *q = vtx(m, t, (k + 1) % 3);
        const double d[3] = {(double)p[0] - q[0], (double)p[1] - q[1], (double)p[2] - q[2]};
        l = fmax(l, sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]));
    }
    *longest = l;
    const double n = ceil(l / spacing);
    return n < 1 ? 1 : n > 4096 ? 4096 : (int)n;
}

static uint32_t tri_count(const void* u, uint64_t t)
{
    const tri_samples* ts = u;
    double l;
    const uint32_t n = (uint32_t)subdivisions(ts->m, t, ts->spacing, &l);
    return (n + 1) * (n + 2) / 2;
}

static void tri_point(const void* u, uint64_t t, uint32_t i, double p[3])
{
    const tri_samples* ts = u;
    double l;
    const int n = subdivisions(ts->m, t, ts->spacing, &l);
    int a = 0;
    while (i > (uint32_t)(n - a)) { /* row a holds n - a + 1 samples */
        i -= (uint32_t)(n - a + 1);
        ++a;
    }
    const double s = (double)a / n, r = (double)i / n;
    const float *v0 = vtx(ts->m, t, 0), *v1 = vtx(ts->m, t, 1), *v2 = vtx(ts->m, t, 2);
    for (int k = 0; k < 3; ++k)
        p[k] = v0[k] + s * ((double)v1[k] - v0[k]) + r * ((double)v2[k] - v0[k]);
}

static double* to_double(const float* f, size_t n)
{
    double* d = malloc(sizeof(double) * (n ? n : 1));
    for (size_t i = 0; d && i < n; ++i)
        d[i] = f[i];
    return d;
}

/* The base mesh's triangles cut for the clipped measurement (>>clipped
 * levels): 9 doubles each. */
typedef struct subtris {
    double* xyz;
    uint64_t count;
} subtris;

/* Triangles, each with its own three vertices (>>clipped levels). */
typedef struct targets {
    double* xyz;
    uint32_t* tri;
    uint64_t count, cap;
} targets;

/* Level 0's drawn surface, collected and gridded once for every
 * measurement of a bake (the stand-in's and each native level's): its
 * faces, their f64 copy and the grid over them, on a box that holds the
 * tile grid and the base mesh (and so every stand-in and level queried). */
struct meso_cells_surface {
    soup s;
    double* fxyz;
    mesoi_tri_grid grid;
    int gridded, too_many;
    double lo[3], hi[3];
    double h;   /* level 0's voxel */
    double big; /* the largest coordinate of the tile grid's box */
    /* What the clipped measurement of native levels reads (>>clipped
     * levels): level 0's solid and the base mesh (borrowed), and a grid
     * over the base mesh, built by the first measurement. */
    const meso_mesh* base;
    meso_voxel_grid g0;
    const meso_split_cells* sc0;
    const meso_membership* mb0;
    int clip_ready;    /* the rest made (once) */
    double* bxyz;
    mesoi_tri_grid bgrid;
    int bgridded;
    subtris st;        /* the base mesh cut for the pieces and targets */
    targets t0;        /* level 0's T, and its grid */
    mesoi_tri_grid t0grid;
    int t0gridded;
};

/* d_A and d_B (see the top) and the stand-in's sampling radius. */
static meso_result distances(meso_cells_surface* f, const meso_mesh* m, double spacing, int threads, double* d_a,
                             double* d_b, double* radius, meso_error* err)
{
    double lo[3], hi[3];
    meso_mesh_bounds(m, lo, hi);
    for (int k = 0; k < 3; ++k) {
        lo[k] = fmin(lo[k], f->lo[k]);
        hi[k] = fmax(hi[k], f->hi[k]);
    }
    double* mxyz = to_double(m->positions, 3 * (size_t)m->vertex_count);
    mesoi_tri_grid gm;
    meso_result r = mxyz ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    int failed = 0;
    if (r == MESO_OK && (r = mesoi_tri_grid_build(mxyz, m->indices, m->triangle_count, lo, hi, &gm, err)) == MESO_OK) {
        const sampler fa = {.blocks = (f->s.faces + FACE_BLOCK - 1) / FACE_BLOCK, .count = face_count,
                            .point = face_centre, .u = &f->s};
        *d_a = sampled_max(&fa, &gm, threads, &failed);
        mesoi_tri_grid_free(&gm);
        const tri_samples ts = {m, spacing};
        const sampler mb = {.blocks = m->triangle_count, .count = tri_count, .point = tri_point, .u = &ts};
        *d_b = sampled_max(&mb, &f->grid, threads, &failed);
    }
    *radius = 0;
    for (uint64_t t = 0; t < m->triangle_count; ++t) {
        double l;
        const int n = subdivisions(m, t, spacing, &l);
        *radius = fmax(*radius, l / n / sqrt(3.0));
    }
    free(mxyz);
    if (r == MESO_OK && failed)
        r = MESO_ERR_OUT_OF_MEMORY;
    if (r == MESO_ERR_OUT_OF_MEMORY)
        return meso_bake_fail(err, r, 0, "cells stand-in: out of memory");
    return r;
}

/* The faces of the solid of `sc` tagged INSIDE by `mb` over `g`, in voxel
 * order. Returns 0 when out of memory; *too_many when there are more than
 * MESO_CELLS_STANDIN_MAX_FACES (the soup is then empty). */
static int collect_faces(const meso_voxel_grid* g, const meso_split_cells* sc, const meso_membership* mb, soup* out,
                         int* too_many)
{
    soup s = {0};
    const int64_t R = g->tile_res;
    uint8_t* inside = calloc((size_t)sc->split_count + 1, 1); /* [0]: empty space, never inside */
    int ok = inside != NULL;
    *too_many = 0;
    /* Pass 0 counts (and stops past the limit), pass 1 lists. */
    for (int pass = 0; pass < 2 && ok; ++pass) {
        if (pass == 1) {
            s.cap = s.faces ? s.faces : 1;
            s.faces = 0;
            s.count_only = 0;
            s.xyz = malloc(sizeof(float) * 12 * s.cap);
            s.tri = malloc(sizeof(uint32_t) * 6 * s.cap);
            s.vox = malloc(sizeof(uint32_t) * s.cap);
            ok = s.xyz && s.tri && s.vox;
        } else {
            s.count_only = 1;
        }
        for (uint32_t tz = 0; ok && tz < g->tiles[2]; ++tz)
            for (uint32_t ty = 0; ok && ty < g->tiles[1]; ++ty)
                for (uint32_t tx = 0; ok && tx < g->tiles[0]; ++tx) {
                    if (meso_membership_tile(mb, tx, ty, tz) == MESO_TILE_OUTSIDE)
                        continue;
                    for (uint32_t sp = 1; sp <= sc->split_count; ++sp) /* this tile's tags, once */
                        inside[sp] = meso_membership_get(mb, tx, ty, tz, sp) == MESO_MEMB_INSIDE;
                    for (int64_t z = 0; ok && z < R; ++z)
                        for (int64_t y = 0; ok && y < R; ++y)
                            for (int64_t x = 0; ok && x < R; ++x) {
                                const int64_t i = tx * R + x, j = ty * R + y, k = tz * R + z;
                                if (!inside[sc->voxel_split[x + R * (y + R * z)]])
                                    continue;
                                for (int dir = 0; ok && dir < 6; ++dir) {
                                    const int64_t step = (dir & 1) ? 1 : -1;
                                    const int a = dir / 2;
                                    const int64_t p[3] = {x + (a == 0) * step, y + (a == 1) * step, z + (a == 2) * step};
                                    const int here = p[0] >= 0 && p[1] >= 0 && p[2] >= 0 && p[0] < R && p[1] < R && p[2] < R;
                                    if (here ? !inside[sc->voxel_split[p[0] + R * (p[1] + R * p[2])]]
                                             : !solid(g, sc, mb, i + (a == 0) * step, j + (a == 1) * step,
                                                      k + (a == 2) * step)) {
                                        if (s.faces == MESO_CELLS_STANDIN_MAX_FACES) {
                                            *too_many = 1;
                                            ok = 0;
                                        } else {
                                            ok = add_face(&s, g, i, j, k, dir);
                                        }
                                    }
                                }
                            }
                }
    }
    free(inside);
    if (*too_many) {
        free(s.xyz);
        free(s.tri);
        free(s.vox);
        s.xyz = NULL;
        s.tri = NULL;
        s.vox = NULL;
        ok = 1;
    }
    *out = s;
    return ok;
}

meso_result meso_cells_surface_build(const meso_mesh* base, const meso_voxel_grid* g, const meso_split_cells* sc,
                                     const meso_membership* mb, meso_cells_surface** out, meso_error* err)
{
    *out = NULL;
    if (!base || !base->triangle_count || !g || !sc || !mb || sc->res != g->tile_res)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "cells stand-in: no mesh, or split cells and grid disagree");
    meso_cells_surface* f = calloc(1, sizeof *f);
    if (!f)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells stand-in: out of memory");
    f->h = g->voxel_size;
    f->base = base;
    f->g0 = *g;
    f->sc0 = sc;
    f->mb0 = mb;
    meso_mesh_bounds(base, f->lo, f->hi);
    for (int k = 0; k < 3; ++k) {
        const double a = g->origin[k], b = g->origin[k] + (double)g->tiles[k] * g->tile_res * g->voxel_size;
        f->lo[k] = fmin(f->lo[k], a);
        f->hi[k] = fmax(f->hi[k], b);
        f->big = fmax(f->big, fmax(fabs(a), fabs(b)));
    }
    meso_result r = MESO_OK;
    if (!collect_faces(g, sc, mb, &f->s, &f->too_many))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0,
                           "cells stand-in: out of memory for the surface's voxel faces (%llu so far)",
                           (unsigned long long)f->s.faces);
    if (r == MESO_OK && !f->too_many && f->s.faces) {
        f->fxyz = to_double(f->s.xyz, 12 * (size_t)f->s.faces);
        r = f->fxyz ? mesoi_tri_grid_build(f->fxyz, f->s.tri, (uint32_t)(2 * f->s.faces), f->lo, f->hi, &f->grid, err)
                    : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells stand-in: out of memory");
        f->gridded = r == MESO_OK;
    }
    if (r != MESO_OK) {
        meso_cells_surface_free(f);
        return r;
    }
    *out = f;
    return MESO_OK;
}

uint64_t meso_cells_surface_faces(const meso_cells_surface* f, int* too_many)
{
    *too_many = f->too_many;
    return f->s.faces;
}

void meso_cells_surface_free(meso_cells_surface* f)
{
    if (!f)
        return;
    if (f->gridded)
        mesoi_tri_grid_free(&f->grid);
    if (f->bgridded)
        mesoi_tri_grid_free(&f->bgrid);
    if (f->t0gridded)
        mesoi_tri_grid_free(&f->t0grid);
    free(f->t0.xyz);
    free(f->t0.tri);
    free(f->st.xyz);
    free(f->bxyz);
    free(f->fxyz);
    free(f->s.xyz);
    free(f->s.tri);
    free(f->s.vox);
    free(f);
}

meso_result meso_cells_standin_measure(const meso_mesh* m, meso_cells_surface* f, int threads,
                                       meso_cells_standin_error* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    if (!m || !m->triangle_count || !f)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "cells stand-in: no mesh or no surface");
    out->faces = f->s.faces;
    out->too_many = f->too_many;
    if (f->too_many || f->s.faces == 0) { /* not measured, or nothing drawn: no bound */
        out->bound = INFINITY;
        return MESO_OK;
    }
    const double h = f->h;
    double d_a = 0, d_b = 0, rad = 0;
    const meso_result r = distances(f, m, 1.001 * sqrt(2.0) * h, threads, &d_a, &d_b, &rad, err);
    if (r != MESO_OK)
        return r;
    const double both = fmax(d_a + sqrt(0.5) * h, d_b + rad);
    double big = f->big;
    for (uint32_t v = 0; v < m->vertex_count; ++v)
        for (int k = 0; k < 3; ++k)
            big = fmax(big, fabs((double)m->positions[3 * (size_t)v + (size_t)k]));
    out->sampled = fmax(d_a, d_b);
    out->radius = fmax(rad, sqrt(0.5) * h);
    out->bound = both + 0.5 * sqrt(3.0) * h + 8.0 * FLT_EPSILON * big;
    return MESO_OK;
}

/* >>clipped levels. The bound above chains the unclipped surfaces with
 * worst cases for the clipping, sqrt(3) (hL + h0 / 2): on spot's level 1
 * that is 4.3 of its 7.0 level-0 voxels, while the reference's hits on the
 * two levels lie at most 1.6 voxels apart (tests/integration/
 * test_cells_standin.c). Measured here instead, each way, on the clipped
 * surfaces themselves: C = (F ∩ M_in) ∪ (∂M ∩ S) for a level's solid S,
 * its faces F and the base mesh M (the top of this file).
 *
 * For sup over x in C_X of d(x, C_Y), an upper bound is the largest
 * d(centre, T) + radius over pieces (a centre, every point of the piece
 * within radius of it) that cover C_X, with T any part of C_Y:
 *  - the pieces: every face of F_X (a superset of F_X ∩ M_in), cut into
 *    squares of level 0's voxel h0 (radius h0 / sqrt 2), and every
 *    sub-triangle of the base mesh (cut to edges of at most h0, as
 *    surface_distance.c cuts) whose box touches a SOLID voxel of level X
 *    (a superset of ∂M ∩ S_X; radius the farthest corner from its
 *    centroid);
 *  - T: the sub-triangles whose box touches SOLID voxels of level Y only
 *    (they lie in ∂M ∩ S_Y), and the faces of F_Y certified inside the
 *    mesh: with y the face's centre, c the centre of a SOLID level-0 voxel
 *    in the face's voxel (inside the mesh, membership.h) and rho the
 *    distance from y to M, rho > |y - c| and rho > the face's half
 *    diagonal put c and the face in one ball that M does not cross, so
 *    inside with c.
 * Both maxima go through sampled_max; the result is the larger way plus
 * the 8 f32 ulps of the largest coordinate as above. A level takes it,
 * and the chained bound only where it is not measured (on spot, 256
 * voxels across, levels 1-3: 0.0228, 0.0350, 0.0678 against the chained
 * 0.0492, 0.0833, 0.164; the bake 1.2 -> 1.7 s, 108 -> 191 MB). It assumes
 * what the chained bound assumes of "inside" (the voxelizer's: exact for
 * parity on a closed mesh). Sub-triangles are limited to
 * CLIPPED_MAX_SUBTRIANGLES (a finer mesh or grid keeps the chained bound). */
enum { CLIPPED_MAX_SUBTRIANGLES = 1 << 23 };

typedef struct level_view {
    const meso_voxel_grid* g;
    const meso_split_cells* sc;
    const meso_membership* mb;
} level_view;

/* Whether every voxel of `v` the box [lo, hi] touches is SOLID (all = 1),
 * or some is (all = 0); boxes are widened by 1e-9 voxel at the voxels'
 * borders, so a point on one counts in both. */
static int box_solid(const level_view* v, const double lo[3], const double hi[3], int all)
{
    int64_t a[3], b[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = (int64_t)floor((lo[k] - v->g->origin[k]) / v->g->voxel_size - 1e-9);
        b[k] = (int64_t)floor((hi[k] - v->g->origin[k]) / v->g->voxel_size + 1e-9);
    }
    for (int64_t k = a[2]; k <= b[2]; ++k)
        for (int64_t j = a[1]; j <= b[1]; ++j)
            for (int64_t i = a[0]; i <= b[0]; ++i) {
                const int s = solid(v->g, v->sc, v->mb, i, j, k);
                if (all && !s)
                    return 0;
                if (!all && s)
                    return 1;
            }
    return all;
}

/* The base mesh's triangles cut into n x n similar ones (n = ceil(longest
 * edge / spacing)), corners of one sub-triangle in turn; 0 past
 * CLIPPED_MAX_SUBTRIANGLES or out of memory. */
static int subtris_make(const meso_mesh* m, double spacing, subtris* out)
{
    memset(out, 0, sizeof *out);
    uint64_t total = 0;
    for (uint64_t t = 0; t < m->triangle_count; ++t) {
        double l;
        const uint64_t n = (uint64_t)subdivisions(m, t, spacing, &l);
        total += n * n;
        if (total > CLIPPED_MAX_SUBTRIANGLES)
            return 0;
    }
    out->xyz = malloc(sizeof(double) * 9 * (total ? total : 1));
    if (!out->xyz)
        return 0;
    for (uint64_t t = 0; t < m->triangle_count; ++t) {
        double l;
        const int n = subdivisions(m, t, spacing, &l);
        const float *v0 = vtx(m, t, 0), *v1 = vtx(m, t, 1), *v2 = vtx(m, t, 2);
        for (int a = 0; a < n; ++a)
            for (int i = 0; a + i < n; ++i)
                for (int up = 0; up < 2; ++up) {
                    if (!up && a + i > n - 2)
                        continue;
                    /* up: (a, i), (a + 1, i), (a, i + 1); down: (a + 1, i), (a + 1, i + 1), (a, i + 1) */
                    const int c[3][2] = {{up ? a : a + 1, i}, {a + 1, up ? i : i + 1}, {a, i + 1}};
                    double* p = out->xyz + 9 * out->count++;
                    for (int q = 0; q < 3; ++q)
                        for (int k = 0; k < 3; ++k)
                            p[3 * q + k] = v0[k] + (double)c[q][0] / n * ((double)v1[k] - v0[k]) +
                                           (double)c[q][1] / n * ((double)v2[k] - v0[k]);
                }
    }
    return 1;
}

static void subtri_box(const double* p, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; ++k) {
        lo[k] = fmin(p[k], fmin(p[3 + k], p[6 + k]));
        hi[k] = fmax(p[k], fmax(p[3 + k], p[6 + k]));
    }
}

/* Appends triangle abc to a target list (vertices each their own); 0 out
 * of memory or past 2^32 / 3 triangles. */
static int targets_add(targets* t, const double* a, const double* b, const double* c)
{
    if (t->count == t->cap) {
        const uint64_t cap = t->cap ? 2 * t->cap : 4096;
        if (cap > UINT32_MAX / 3)
            return 0;
        double* x = realloc(t->xyz, sizeof(double) * 9 * cap);
        if (x)
            t->xyz = x;
        uint32_t* i = realloc(t->tri, sizeof(uint32_t) * 3 * cap);
        if (i)
            t->tri = i;
        if (!x || !i)
            return 0;
        t->cap = cap;
    }
    memcpy(t->xyz + 9 * t->count, a, 3 * sizeof(double));
    memcpy(t->xyz + 9 * t->count + 3, b, 3 * sizeof(double));
    memcpy(t->xyz + 9 * t->count + 6, c, 3 * sizeof(double));
    for (int q = 0; q < 3; ++q)
        t->tri[3 * t->count + (uint64_t)q] = (uint32_t)(3 * t->count + (uint64_t)q);
    ++t->count;
    return 1;
}

/* A face's corners (soup order: 0, 1, 2, 3 around) and centre. */
static void face_corners(const soup* s, uint64_t f, double c[4][3], double centre[3])
{
    const float* q = s->xyz + 12 * f;
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k)
            c[i][k] = q[3 * i + k];
    for (int k = 0; k < 3; ++k)
        centre[k] = 0.5 * (c[0][k] + c[2][k]);
}

/* Whether face f of level v's soup lies inside the mesh (the certificate
 * at the top of this section). `g0` is level 0's solid, `bg` the base
 * mesh's grid (this thread's copy). */
static int face_certified(const soup* s, uint64_t f, const level_view* v, const level_view* g0, mesoi_tri_grid* bg)
{
    double c[4][3], y[3];
    face_corners(s, f, c, y);
    const double h = v->g->voxel_size, h0 = g0->g->voxel_size;
    int axis = 0;
    for (int k = 0; k < 3; ++k)
        if (c[0][k] == c[1][k] && c[0][k] == c[2][k])
            axis = k;
    /* The face's SOLID voxel: the one of the two beside it that is SOLID. */
    int64_t vi[3] = {0, 0, 0};
    int found = 0;
    for (int side = -1; side <= 1 && !found; side += 2) {
        double q[3] = {y[0], y[1], y[2]};
        q[axis] += side * 0.5 * h;
        for (int k = 0; k < 3; ++k)
            vi[k] = (int64_t)floor((q[k] - v->g->origin[k]) / h);
        found = solid(v->g, v->sc, v->mb, vi[0], vi[1], vi[2]);
    }
    if (!found)
        return 0;
    /* The nearest centre of a SOLID level-0 voxel inside it. */
    const int64_t n = (int64_t)llround(h / h0);
    double best = INFINITY;
    for (int64_t dz = 0; dz < n; ++dz)
        for (int64_t dy = 0; dy < n; ++dy)
            for (int64_t dx = 0; dx < n; ++dx) {
                const int64_t i = vi[0] * n + dx, j = vi[1] * n + dy, k = vi[2] * n + dz;
                if (!solid(g0->g, g0->sc, g0->mb, i, j, k))
                    continue;
                const int64_t ijk[3] = {i, j, k};
                double d2 = 0;
                for (int a = 0; a < 3; ++a) {
                    const double e = g0->g->origin[a] + ((double)ijk[a] + 0.5) * h0 - y[a];
                    d2 += e * e;
                }
                best = fmin(best, sqrt(d2));
            }
    if (!isfinite(best))
        return 0;
    const double need = (1.0 + 1e-9) * fmax(best, sqrt(0.5) * h) + 1e-12 * (1.0 + fabs(y[0]) + fabs(y[1]) + fabs(y[2]));
    return mesoi_tri_grid_distance_within(bg, y, 2.0 * need) > need; /* rho > need */
}

/* The pieces of C_X: face squares of h0 (blocks of one face) and
 * sub-triangles touching S_X (blocks of FACE_BLOCK of them). */
typedef struct face_pieces {
    const soup* s;
    int n; /* squares a face edge */
} face_pieces;

/* FACE_BLOCK consecutive faces a block (neighbours in voxel order, so
 * sampled_max skips most of them). */
static uint32_t square_count(const void* u, uint64_t b)
{
    const face_pieces* fp = u;
    return face_count(fp->s, b) * (uint32_t)(fp->n * fp->n);
}

static void square_centre(const void* u, uint64_t b, uint32_t i, double p[3])
{
    const face_pieces* fp = u;
    const uint32_t nn = (uint32_t)(fp->n * fp->n), sq = i % nn;
    double c[4][3], centre[3];
    face_corners(fp->s, b * FACE_BLOCK + i / nn, c, centre);
    const double su = ((double)(sq % (uint32_t)fp->n) + 0.5) / fp->n, sv = ((double)(sq / (uint32_t)fp->n) + 0.5) / fp->n;
    for (int k = 0; k < 3; ++k)
        p[k] = c[0][k] + su * (c[1][k] - c[0][k]) + sv * (c[3][k] - c[0][k]);
}

typedef struct tri_pieces {
    const double* xyz;  /* the sub-triangles (subtris) */
    const uint64_t* of; /* the chosen ones */
    uint64_t count;
} tri_pieces;

static uint32_t piece_count(const void* u, uint64_t b)
{
    return block_items(((const tri_pieces*)u)->count, b);
}

static void piece_centroid(const void* u, uint64_t b, uint32_t i, double p[3])
{
    const tri_pieces* tp = u;
    const double* q = tp->xyz + 9 * tp->of[b * FACE_BLOCK + i];
    for (int k = 0; k < 3; ++k)
        p[k] = (q[k] + q[3 + k] + q[6 + k]) / 3.0;
}

/* T for level Y (the top of this section): its certified faces, two
 * triangles each, and the sub-triangles in S_Y; gridded into *tg when
 * there are any (*gridded). Certificates are one verdict a face, so the
 * threads do not change them. */
static meso_result level_targets(meso_cells_surface* f, const level_view* y, const soup* sy, int threads, targets* t,
                                 mesoi_tri_grid* tg, int* gridded, meso_error* err)
{
    const level_view v0 = {&f->g0, f->sc0, f->mb0};
    memset(t, 0, sizeof *t);
    *gridded = 0;
    uint8_t* ok = calloc(sy->faces ? sy->faces : 1, 1);
    int failed = !ok;
    const int nth = meso_bake_thread_count(threads);
#ifdef _OPENMP
#pragma omp parallel num_threads(nth) reduction(| : failed)
#endif
    {
        mesoi_tri_grid mine = f->bgrid;
        mine.stamp = calloc(f->bgrid.nt ? f->bgrid.nt : 1, sizeof(uint32_t));
        mine.query = 0;
        failed |= !mine.stamp;
#ifdef _OPENMP
#pragma omp for schedule(dynamic, 256)
#endif
        for (int64_t i = 0; i < (int64_t)sy->faces; ++i)
            if (mine.stamp && ok)
                ok[i] = (uint8_t)face_certified(sy, (uint64_t)i, y, &v0, &mine);
        free(mine.stamp);
    }
#ifndef _OPENMP
    (void)nth;
#endif
    for (uint64_t i = 0; !failed && i < sy->faces; ++i)
        if (ok[i]) {
            double c[4][3], centre[3];
            face_corners(sy, i, c, centre);
            failed = !targets_add(t, c[0], c[1], c[2]) || !targets_add(t, c[0], c[2], c[3]);
        }
    for (uint64_t i = 0; !failed && i < f->st.count; ++i) {
        const double* p = f->st.xyz + 9 * i;
        double lo[3], hi[3];
        subtri_box(p, lo, hi);
        if (box_solid(y, lo, hi, 1))
            failed = !targets_add(t, p, p + 3, p + 6);
    }
    free(ok);
    if (failed)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells level: out of memory measuring the clipped surfaces");
    if (!t->count)
        return MESO_OK;
    const meso_result r = mesoi_tri_grid_build(t->xyz, t->tri, (uint32_t)t->count, f->lo, f->hi, tg, err);
    *gridded = r == MESO_OK;
    return r;
}

/* sup over C_X of d(., C_Y) as above, with T of level Y gridded in tg. */
static meso_result clipped_way(meso_cells_surface* f, const level_view* x, const soup* sx, const mesoi_tri_grid* tg,
                               int threads, double* out, meso_error* err)
{
    uint64_t* chosen = malloc(sizeof(uint64_t) * (f->st.count ? f->st.count : 1));
    tri_pieces pieces = {.xyz = f->st.xyz, .of = chosen};
    int failed = !chosen;
    double rmax = 0;
    for (uint64_t i = 0; !failed && i < f->st.count; ++i) {
        const double* p = f->st.xyz + 9 * i;
        double lo[3], hi[3];
        subtri_box(p, lo, hi);
        if (!box_solid(x, lo, hi, 0))
            continue;
        chosen[pieces.count++] = i;
        for (int q = 0; q < 3; ++q) {
            double d2 = 0;
            for (int k = 0; k < 3; ++k) {
                const double e = p[3 * q + k] - (p[k] + p[3 + k] + p[6 + k]) / 3.0;
                d2 += e * e;
            }
            rmax = fmax(rmax, sqrt(d2));
        }
    }
    *out = INFINITY;
    if (!failed) {
        const face_pieces fp = {sx, (int)llround(x->g->voxel_size / f->h)};
        const sampler sf = {.blocks = (sx->faces + FACE_BLOCK - 1) / FACE_BLOCK, .count = square_count,
                            .point = square_centre, .u = &fp};
        const double d_faces = sampled_max(&sf, tg, threads, &failed);
        const sampler sp = {.blocks = (pieces.count + FACE_BLOCK - 1) / FACE_BLOCK, .count = piece_count,
                            .point = piece_centroid, .u = &pieces};
        const double d_tris = pieces.count ? sampled_max(&sp, tg, threads, &failed) : 0.0;
        *out = fmax(d_faces + sqrt(0.5) * f->h, pieces.count ? d_tris + rmax : 0.0);
    }
    free(chosen);
    if (failed)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells level: out of memory measuring the clipped surfaces");
    return MESO_OK;
}

/* The clipped bound of level L (vl, its faces sl) against level 0, both
 * ways; +inf when not measured (too many sub-triangles, nothing
 * certified). What depends on level 0 alone (the base mesh's grid, the
 * sub-triangles, level 0's T) is made by the first level and kept in f. */
static meso_result clipped_bound(meso_cells_surface* f, const level_view* vl, const soup* sl, int threads,
                                 double* out, meso_error* err)
{
    *out = INFINITY;
    meso_result r = MESO_OK;
    if (!f->clip_ready) {
        f->clip_ready = 1;
        f->bxyz = to_double(f->base->positions, 3 * (size_t)f->base->vertex_count);
        if (!f->bxyz)
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells level: out of memory");
        if ((r = mesoi_tri_grid_build(f->bxyz, f->base->indices, f->base->triangle_count, f->lo, f->hi, &f->bgrid,
                                      err)) != MESO_OK)
            return r;
        f->bgridded = 1;
        if (!subtris_make(f->base, f->h, &f->st))
            return MESO_OK; /* too many (or no memory for them): the chained bound stands */
        const level_view v0 = {&f->g0, f->sc0, f->mb0};
        if ((r = level_targets(f, &v0, &f->s, threads, &f->t0, &f->t0grid, &f->t0gridded, err)) != MESO_OK)
            return r;
    }
    if (!f->st.xyz || !f->t0gridded)
        return MESO_OK;
    const level_view v0 = {&f->g0, f->sc0, f->mb0};
    targets tl;
    mesoi_tri_grid tlgrid;
    int tlgridded = 0;
    double a = INFINITY, b = INFINITY;
    r = level_targets(f, vl, sl, threads, &tl, &tlgrid, &tlgridded, err);
    if (r == MESO_OK && tlgridded)
        r = clipped_way(f, &v0, &f->s, &tlgrid, threads, &a, err);
    if (r == MESO_OK && tlgridded)
        r = clipped_way(f, vl, sl, &f->t0grid, threads, &b, err);
    if (tlgridded)
        mesoi_tri_grid_free(&tlgrid);
    free(tl.xyz);
    free(tl.tri);
    if (r == MESO_OK)
        *out = fmax(a, b) + 8.0 * FLT_EPSILON * f->big;
    return r;
}

/* >>native levels. A coarser level L of the same object (cells_levels.h)
 * against level 0: level L's voxel faces, as a triangle soup, take the
 * stand-in's place above, which bounds the two-sided distance H between
 * the two unclipped solids' surfaces F0 and FL and adds h0 sqrt(3) / 2.
 * What libmeso draws is each solid clipped to the base mesh (the top of
 * this file), C0 and CL:
 *  - a point of F0 outside the mesh is within h0 sqrt(3) / 2 of C0 (the
 *    crossing argument above: every SOLID level-0 voxel's centre is inside
 *    the mesh, membership.h);
 *  - level L's tags are inherited, so a SOLID level-L voxel only contains
 *    a SOLID level-0 voxel, whose centre is inside the mesh and at most
 *    sqrt(3) (hL - h0 / 2) from any point of the coarse voxel: a point of
 *    FL outside the mesh is within that of CL (the same crossing, towards
 *    that centre);
 *  - a point of the mesh inside a solid is near its faces where the mesh
 *    is flat at the scale of a voxel: moving out along the normal, a voxel
 *    all of whose points are outside holds no centre inside, so it is not
 *    SOLID: within h0 sqrt(3) / 2 of F0 (its own centre decides), within
 *    hL sqrt(3) of FL (any of its level-0 centres does).
 * Chaining them each way (C0 -> F0 -> FL -> CL and CL -> FL -> F0 -> C0),
 *
 *     bound = H + sqrt(3) (hL + h0 / 2),
 *
 * the error of a native level where the clipped surfaces are not measured
 * (>>clipped levels, which a level takes otherwise; a mesh with folds
 * thinner than a voxel can exceed this one; the stand-in bound above
 * assumes as much of the clipped solid). tests/integration/
 * test_cells_standin.c checks a level's error against the exact
 * reference's unclipped hits and against its hits traced from where the
 * rays enter the mesh, both ways. */
meso_result meso_cells_level_measure(meso_cells_surface* f0, const meso_voxel_grid* gl, const meso_split_cells* scl,
                                     const meso_membership* mbl, int threads, meso_cells_standin_error* out,
                                     meso_error* err)
{
    memset(out, 0, sizeof(*out));
    if (!gl || !scl || !mbl || scl->res != gl->tile_res)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "cells level: split cells and grid disagree");
    soup s;
    int too_many = 0;
    if (!collect_faces(gl, scl, mbl, &s, &too_many)) {
        free(s.xyz);
        free(s.tri);
        free(s.vox);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells level: out of memory for its voxel faces");
    }
    if (too_many || s.faces == 0) { /* nothing drawn, or too much to measure: no bound */
        out->faces = s.faces;
        out->too_many = too_many;
        out->bound = INFINITY;
        free(s.xyz);
        free(s.tri);
        free(s.vox);
        return MESO_OK;
    }
    /* The clipped surfaces measured (>>clipped levels); the chained bound
     * where they cannot be. */
    double clipped = INFINITY;
    const level_view vl = {gl, scl, mbl};
    meso_result r = clipped_bound(f0, &vl, &s, threads, &clipped, err);
    out->faces = s.faces;
    out->clipped = clipped;
    out->chained = INFINITY;
    out->bound = clipped;
    if (r == MESO_OK && !isfinite(clipped)) {
        const meso_mesh faces = {.vertex_count = (uint32_t)(4 * s.faces), .triangle_count = (uint32_t)(2 * s.faces),
                                 .positions = s.xyz, .indices = s.tri};
        r = meso_cells_standin_measure(&faces, f0, threads, out, err);
        if (r == MESO_OK) /* the standin measure added h0 sqrt(3) / 2 */
            out->bound += sqrt(3.0) * gl->voxel_size;
        out->clipped = INFINITY;
        out->chained = out->bound;
    }
    free(s.xyz);
    free(s.tri);
    free(s.vox);
    return r;
}

/* >>appearance. What level 0 shows at a point of a stand-in: the colour of
 * the voxel whose face is nearest (the face the stand-in is measured
 * against), as cells_frag.glsl colours a hit on it: COLR's texel of the
 * voxel, or the mesh's colour grid trilinear at the face's point. Cells
 * are not darkened: occlusion 1. */
static void cells_at(const mesoi_appearance* a, mesoi_tri_grid* grid, uint32_t t, const double b[3],
                     const double p[3], float out[4])
{
    (void)t;
    (void)b;
    const meso_cells_colours* c = a->ctx;
    uint32_t tri = 0;
    double bw[2];
    mesoi_tri_grid_closest(grid, p, &tri, bw);
    out[3] = 1.0f;
    if (!c->grid) {
        const uint8_t* q = c->colr + 4 * (size_t)c->vox[tri / 2];
        for (int k = 0; k < 3; ++k)
            out[k] = (float)meso_srgb8_to_linear(q[k]);
        return;
    }
    /* The face's point, then the grid's sample coordinates (clamped to
     * [0, G - 1]) as the shader computes them. */
    const uint32_t* v = grid->tri + 3 * (size_t)tri;
    double x[3];
    int i0[3], i1[3];
    for (int k = 0; k < 3; ++k) {
        const double q = (1 - bw[0] - bw[1]) * grid->xyz[3 * (size_t)v[0] + k] + bw[0] * grid->xyz[3 * (size_t)v[1] + k] +
                         bw[1] * grid->xyz[3 * (size_t)v[2] + k];
        const double G = c->grid_dims[k];
        x[k] = fmin(fmax((q - c->origin[k]) / c->extent[k] * G - 0.5, 0.0), G - 1);
        i0[k] = (int)x[k];
        if (i0[k] > (int)G - 1)
            i0[k] = (int)G - 1;
        i1[k] = i0[k] + 1 < (int)G ? i0[k] + 1 : (int)G - 1;
        x[k] -= i0[k];
    }
    double rgb[3] = {0, 0, 0};
    for (int corner = 0; corner < 8; ++corner) {
        const int ix = corner & 1 ? i1[0] : i0[0], iy = corner & 2 ? i1[1] : i0[1], iz = corner & 4 ? i1[2] : i0[2];
        const double w = (corner & 1 ? x[0] : 1 - x[0]) * (corner & 2 ? x[1] : 1 - x[1]) * (corner & 4 ? x[2] : 1 - x[2]);
        const uint8_t* q = c->grid + 4 * ((size_t)ix + c->grid_dims[0] * ((size_t)iy + (size_t)c->grid_dims[1] * iz));
        for (int k = 0; k < 3; ++k)
            rgb[k] += w * meso_srgb8_to_linear(q[k]);
    }
    for (int k = 0; k < 3; ++k)
        out[k] = (float)rgb[k];
}

int meso_cells_surface_appearance(const meso_cells_surface* f, meso_cells_colours* c, mesoi_appearance* out)
{
    if (!f->gridded)
        return 0;
    c->vox = f->s.vox;
    /* A query from a stand-in point may search tens of voxels out (the
     * stand-in is up to its error from the faces): 2 x 2 sub-triangles at
     * most. Against 4 x 4 on spot: 158 ms instead of 448, the stand-ins'
     * block colour error in test_rt_standin_colour 14.27 instead of 14.38. */
    *out = (mesoi_appearance){.at = cells_at, .grid = &f->grid, .ctx = c, .subdivisions = 2};
    return 1;
}
