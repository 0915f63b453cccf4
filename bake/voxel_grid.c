/*
 * voxel_grid.c — the voxelizer's grid of tiles (voxelize.h: N = tiles x
 * tile_res voxels per axis, centres at origin + (i + 1/2) h), the spans of
 * tiles and voxel centres a box covers, and the triangle-box overlap test
 * that makes a tile a candidate (separating axes, Akenine-Moeller, "Fast 3D
 * Triangle-Box Overlap Testing", 2001).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "vec3d.h"
#include "voxelize_internal.h"

/* >>triangle-box overlap ---------------------------------------------------------
 * Separating axes (Akenine-Moeller, "Fast 3D Triangle-Box Overlap Testing",
 * 2001): the box's three axes, the triangle's normal, and the nine edge x
 * box-axis products. Callers grow the box, so rounding can only add overlaps. */
int mesoi_tri_box(const double centre[3], const double half[3], const double* tv /* 3 corners */)
{
    double v[3][3], e[3][3];
    for (int c = 0; c < 3; ++c)
        sub3(tv + 3 * c, centre, v[c]);
    for (int k = 0; k < 3; ++k) {
        if (mesoi_dmin(v[0][k], mesoi_dmin(v[1][k], v[2][k])) > half[k] ||
            mesoi_dmax(v[0][k], mesoi_dmax(v[1][k], v[2][k])) < -half[k])
            return 0;
        for (int c = 0; c < 3; ++c)
            e[c][k] = v[(c + 1) % 3][k] - v[c][k];
    }
    double n[3];
    cross3(e[0], e[1], n);
    const double rn = half[0] * fabs(n[0]) + half[1] * fabs(n[1]) + half[2] * fabs(n[2]);
    if (fabs(dot3(n, v[0])) > rn)
        return 0;
    for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) { /* axis = unit_k x e_c */
            double ax[3] = {0, 0, 0};
            const int k1 = (k + 1) % 3, k2 = (k + 2) % 3;
            ax[k1] = -e[c][k2];
            ax[k2] = e[c][k1];
            double lo = INFINITY, hi = -INFINITY;
            for (int j = 0; j < 3; ++j) {
                const double p = dot3(ax, v[j]);
                lo = mesoi_dmin(lo, p);
                hi = mesoi_dmax(hi, p);
            }
            const double r = half[0] * fabs(ax[0]) + half[1] * fabs(ax[1]) + half[2] * fabs(ax[2]);
            if (lo > r || hi < -r)
                return 0;
        }
    return 1;
}

int meso_triangle_box_overlap(const double centre[3], const double half[3], const double tv[9])
{
    return mesoi_tri_box(centre, half, tv);
}

/* >>grid ---------------------------------------------------------------------- */

void meso_voxel_center(const meso_voxel_grid* g, uint32_t i, uint32_t j, uint32_t k, double out[3])
{
    out[0] = g->origin[0] + ((double)i + 0.5) * g->voxel_size;
    out[1] = g->origin[1] + ((double)j + 0.5) * g->voxel_size;
    out[2] = g->origin[2] + ((double)k + 0.5) * g->voxel_size;
}

/* Tiles whose closed (grown) box along `axis` can meet [lo, hi], clamped to
 * the grid; returns 0 when none. */
int mesoi_tile_span(const mesoi_grid* g, int axis, double lo, double hi, uint32_t* t0, uint32_t* t1)
{
    const double a = floor((lo - g->o[axis]) / g->tile - 1e-6), b = floor((hi - g->o[axis]) / g->tile + 1e-6);
    if (b < 0 || a >= g->T[axis] || !(a <= b))
        return 0;
    *t0 = a < 0 ? 0 : (uint32_t)a;
    *t1 = b >= g->T[axis] ? g->T[axis] - 1 : (uint32_t)b;
    return 1;
}

/* Voxel centres along `axis` within [lo, hi] (one more on each side), in
 * [first, last] clamped to [c0, c1]; returns 0 when none. */
int mesoi_centre_span(const mesoi_grid* g, int axis, double lo, double hi, int64_t c0, int64_t c1, int64_t* i0,
                       int64_t* i1)
{
    double fa = (lo - g->o[axis]) / g->h, fb = (hi - g->o[axis]) / g->h;
    if (!(fa <= fb) || fb < (double)c0 - 2.0 || fa > (double)c1 + 2.0)
        return 0;
    fa = mesoi_dmax(fa, (double)c0 - 4.0); /* keeps the conversions below in range */
    fb = mesoi_dmin(fb, (double)c1 + 4.0);
    /* ceil(fa - 1/2) - 1, floor(fb - 1/2) + 1 */
    const double a = -mesoi_ffloor(0.5 - fa) - 1, b = mesoi_ffloor(fb - 0.5) + 1;
    if (!(a <= b) || b < (double)c0 || a > (double)c1)
        return 0;
    *i0 = a < (double)c0 ? c0 : (int64_t)a;
    *i1 = b > (double)c1 ? c1 : (int64_t)b;
    return 1;
}

uint64_t meso_voxel_tile_words(uint32_t tile_res)
{
    const uint64_t r = tile_res;
    return (r * r * r + 63) / 64;
}

const char* meso_voxelizer_name(meso_voxelizer v)
{
    switch (v) {
    case MESO_VOXELIZE_AUTO: return "auto";
    case MESO_VOXELIZE_PARITY: return "parity";
    case MESO_VOXELIZE_WINDING: return "winding";
    default: return "?";
    }
}

meso_result mesoi_check_grid(const meso_voxel_grid* vg, mesoi_grid* g, meso_error* err)
{
    if (!(vg->voxel_size > 0.0) || !isfinite(vg->voxel_size) || vg->tile_res < 1 ||
        vg->tile_res > MESO_VOXELIZE_MAX_TILE_RES)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                              "voxelize: voxel size %g or tile resolution %u out of range (1..%u)", vg->voxel_size,
                              vg->tile_res, MESO_VOXELIZE_MAX_TILE_RES);
    memset(g, 0, sizeof(*g));
    g->R = vg->tile_res;
    g->h = vg->voxel_size;
    g->tile = g->h * g->R;
    double extent = 0.0;
    for (int a = 0; a < 3; ++a) {
        if (vg->tiles[a] < 1 || (uint64_t)vg->tiles[a] * vg->tile_res > MESO_VOXELIZE_MAX_RES ||
            !isfinite(vg->origin[a]))
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                                  "voxelize: %u tiles of %u voxels along axis %d: more than %u voxels (or a "
                                  "non-finite origin)",
                                  vg->tiles[a], vg->tile_res, a, MESO_VOXELIZE_MAX_RES);
        g->o[a] = vg->origin[a];
        g->T[a] = vg->tiles[a];
        g->N[a] = vg->tiles[a] * vg->tile_res;
        extent = mesoi_dmax(extent, fabs(g->o[a]) + g->N[a] * g->h);
    }
    g->margin = 1e-6 * g->h + 1e-12 * extent;
    return MESO_OK;
}

meso_result meso_voxel_grid_fit(const meso_mesh* m, uint32_t tiles, uint32_t tile_res, double pad,
                                meso_voxel_grid* out, meso_error* err)
{
    if (!m || !out || !m->positions || m->vertex_count == 0)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID, "voxel grid: no mesh");
    memset(out, 0, sizeof(*out));
    const uint64_t n = (uint64_t)tiles * tile_res;
    if (tiles < 1 || tile_res < 1 || tile_res > MESO_VOXELIZE_MAX_TILE_RES || n > MESO_VOXELIZE_MAX_RES ||
        !(pad >= 0.0) || !(2.0 * pad < (double)n))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                              "voxel grid: %u tiles x %u voxels with %g voxels of padding: out of range (at most "
                              "%u voxels per axis)",
                              tiles, tile_res, pad, MESO_VOXELIZE_MAX_RES);
    double lo[3], hi[3];
    (void)meso_mesh_bounds(m, lo, hi);
    const double ext = mesoi_dmax(hi[0] - lo[0], mesoi_dmax(hi[1] - lo[1], hi[2] - lo[2]));
    if (!(ext > 0.0) || !isfinite(ext))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                              "voxel grid: the mesh's bounding box is empty or not finite");
    out->voxel_size = ext / ((double)n - 2.0 * pad);
    out->tile_res = tile_res;
    for (int a = 0; a < 3; ++a) {
        out->tiles[a] = tiles;
        out->origin[a] = 0.5 * (lo[a] + hi[a]) - 0.5 * (double)n * out->voxel_size;
    }
    return MESO_OK;
}
