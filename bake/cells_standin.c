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

/* Cells -> stand-in: face centres, FACE_BLOCK consecutive faces a block. */
static uint32_t face_count(const void* u, uint64_t b)
{
    const soup* s = u;
    const uint64_t left = s->faces - b * FACE_BLOCK;
    return left < FACE_BLOCK ? (uint32_t)left : FACE_BLOCK;
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

/* d_A and d_B (see the top) and the stand-in's sampling radius. */
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
 * decided here as the error of a native level (a mesh with folds thinner
 * than a voxel can exceed it; the stand-in bound above assumes as much of
 * the clipped solid). tests/integration/test_cells_standin.c checks it
 * against the exact reference's (unclipped) hits, both ways. */
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
    const meso_mesh faces = {.vertex_count = (uint32_t)(4 * s.faces), .triangle_count = (uint32_t)(2 * s.faces),
                             .positions = s.xyz, .indices = s.tri};
    const meso_result r = meso_cells_standin_measure(&faces, f0, threads, out, err);
    if (r == MESO_OK) /* the standin measure added h0 sqrt(3) / 2 */
        out->bound += sqrt(3.0) * gl->voxel_size;
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
