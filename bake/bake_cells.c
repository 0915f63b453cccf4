/*
 * bake_cells.c — meso_bake_cells (`mesobake cells`): a cell-based object
 * (cell-based-object-representation.md ch. 3–4) as one .meso cells object:
 * the base mesh, CELL, TILE, SPLT, MEMB, NRMM and COLR (FORMAT.md §7.2
 * kind 3, §7.8). Stages: tile map (tile_map.h) → split cells
 * (split_cells.h) → exact sparse voxelization and membership
 * (voxelize.h, membership.h) → normal and colour maps (cells_chunks.h),
 * and with `--colour from-mesh[:G]` the mesh's base colour as a TX3D colour
 * grid (mesh_colour_grid.h; COLR then holds the default hash colours).
 * Levels of detail (FORMAT.md §7.10, `--levels`): levels 1..N are native,
 * the tile map halved each level (cells_levels.h), each with its error
 * measured against level 0 and kept while it is below the stand-in's;
 * then the base mesh drawn as a plain mesh, its error measured against the
 * voxel faces the object draws (cells_standin.h); coarser levels are the
 * base mesh's simplifications (mesh_levels.h), each with error = the
 * base's + the simplification's (the triangle inequality of Hausdorff
 * distances). `--levels K` keeps at most K in all: level 0, the base mesh
 * (K >= 2), then native levels, then simplified ones.
 * Error messages name the options as mesobake spells them (--tile-map ...).
 */
#include "bake_internal.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "cells_chunks.h"
#include "cells_levels.h"
#include "cells_standin.h"
#include "mesh_colour_grid.h"
#include "memory_budget.h"
#include "mesh_check.h"
#include "mesh_chunk.h"
#include "meso_clock.h"
#include "meso_layout.h"
#include "standin_levels.h"

_Static_assert(MESO_BAKE_MAX_TILES == MESO_VOXELIZE_MAX_RES, "tiles x tile_res share one bound");
_Static_assert(MESO_BAKE_CELLS_MAX_LEVELS == MESOI_STANDIN_MAX_LEVELS, "the stand-ins hold every level");

meso_bake_cells_options meso_bake_cells_defaults(void)
{
    return (meso_bake_cells_options){0};
}

/* "NAME[:A[:B]]": copies NAME, returns how many of A, B were given (-1: bad). */
static int split_spec(const char* spec, char* name, size_t name_size, const char** a, const char** b)
{
    const char* c1 = strchr(spec, ':');
    size_t n = c1 ? (size_t)(c1 - spec) : strlen(spec);
    if (n >= name_size)
        return -1;
    memcpy(name, spec, n);
    name[n] = 0;
    *a = *b = NULL;
    if (!c1)
        return 0;
    *a = c1 + 1;
    const char* c2 = strchr(*a, ':');
    if (!c2)
        return 1;
    *b = c2 + 1;
    return 2;
}

static meso_result make_tile_map(const meso_bake_cells_options* a, uint32_t* res, meso_tile_map* tm, meso_error* err)
{
    char name[16], num[32];
    const char *pa, *pb;
    int given = split_spec(a->tile_map, name, sizeof name, &pa, &pb);
    const int voronoi = given >= 0 && !strcmp(name, "voronoi"), spheres = given >= 0 && !strcmp(name, "spheres");
    if (voronoi || spheres) {
        meso_tile_map_params p = {.kind = voronoi ? MESO_TILE_MAP_VORONOI : MESO_TILE_MAP_SPHERES,
                                  .res = *res ? *res : 32, .count = 8, .radius = 0.25, .rng_seed = 1};
        long count = 8;
        if (given >= 1) {
            size_t n = pb ? (size_t)(pb - 1 - pa) : strlen(pa);
            snprintf(num, sizeof num, "%.*s", (int)(n < sizeof num ? n : sizeof num - 1), pa);
            if (!meso_bake_parse_long(num, 1, MESO_TILE_MAP_MAX_CELLS, &count))
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                                      "--tile-map '%s': count must be an integer in 1..%u", a->tile_map,
                                      MESO_TILE_MAP_MAX_CELLS);
            p.count = (uint32_t)count;
        }
        if (given == 2 && voronoi) {
            char* end = NULL;
            errno = 0;
            p.rng_seed = strtoull(pb, &end, 10);
            if (!end || end == pb || *end || errno || *pb < '0' || *pb > '9') /* no sign, no wrap-around */
                return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                                      "--tile-map '%s': RNG must be a non-negative integer", a->tile_map);
        } else if (given == 2 && (!meso_bake_parse_positive(pb, &p.radius) || p.radius > 1)) {
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                                  "--tile-map '%s': RADIUS must be in (0, 1] tile edges", a->tile_map);
        }
        *res = p.res;
        return meso_tile_map_generate(&p, a->common.threads, tm, err);
    }
    /* FILE.raw:R */
    const char* colon = strrchr(a->tile_map, ':');
    long r = 0;
    if (!colon || !meso_bake_parse_long(colon + 1, 1, MESO_TILE_MAP_MAX_RES, &r))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "--tile-map '%s': expected voronoi[:SEEDS[:RNG]], spheres[:N[:RADIUS]] or FILE.raw:R",
                              a->tile_map);
    if (*res && *res != (uint32_t)r)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "--tile-map '%s' has resolution %ld but --tile-res is %u", a->tile_map, r, *res);
    char path[4096];
    snprintf(path, sizeof path, "%.*s", (int)(colon - a->tile_map), a->tile_map);
    *res = (uint32_t)r;
    return meso_tile_map_read_raw(path, (uint32_t)r, tm, err);
}

/* The grid: --tiles N through meso_voxel_grid_fit; --cell-size S: tiles of
 * edge S, as many as cover the mesh plus one voxel each side, centred. Then
 * origin and voxel size are rounded to f32, the precision CELL stores, so
 * the file states exactly the grid that was classified. */
static meso_result make_grid(const meso_bake_cells_options* a, const meso_mesh* m, uint32_t R, meso_voxel_grid* g,
                             meso_error* err)
{
    meso_result r;
    if (a->cell_size > 0) {
        double lo[3], hi[3], ext = 0;
        meso_mesh_bounds(m, lo, hi);
        for (int k = 0; k < 3; ++k)
            ext = fmax(ext, hi[k] - lo[k]);
        double t = ceil(ext / a->cell_size + 2.0 / R);
        if (!(t >= 1) || t * R > MESO_VOXELIZE_MAX_RES)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                                  "--cell-size %g needs %.0f tiles of %u voxels per axis; at most %u voxels fit",
                                  a->cell_size, t, R, MESO_VOXELIZE_MAX_RES);
        memset(g, 0, sizeof *g);
        g->tile_res = R;
        g->voxel_size = a->cell_size / R;
        for (int k = 0; k < 3; ++k) {
            g->tiles[k] = (uint32_t)t;
            g->origin[k] = 0.5 * (lo[k] + hi[k]) - 0.5 * t * a->cell_size;
        }
        r = MESO_OK;
    } else {
        uint32_t tiles = a->tiles ? (uint32_t)a->tiles : 8;
        if ((uint64_t)tiles * R > MESO_VOXELIZE_MAX_RES)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_GRID,
                                  "%u tiles of %u voxels: %llu voxels per axis, at most %u", tiles, R,
                                  (unsigned long long)tiles * R, MESO_VOXELIZE_MAX_RES);
        r = meso_voxel_grid_fit(m, tiles, R, 1.0, g, err);
    }
    if (r == MESO_OK) {
        for (int k = 0; k < 3; ++k)
            g->origin[k] = (double)(float)g->origin[k];
        g->voxel_size = (double)(float)g->voxel_size;
    }
    return r;
}

/* The tile resolution make_tile_map will use: --tile-res, else the R of
 * FILE.raw:R, else the generators' 32 (a spec that does not parse fails in
 * make_tile_map). */
static uint32_t planned_res(const meso_bake_cells_options* a)
{
    const char* colon = strrchr(a->tile_map, ':');
    long r = 32;
    if (!a->tile_res && strncmp(a->tile_map, "voronoi", 7) && strncmp(a->tile_map, "spheres", 7) && colon &&
        !meso_bake_parse_long(colon + 1, 1, MESO_TILE_MAP_MAX_RES, &r))
        r = 32;
    return a->tile_res ? (uint32_t)a->tile_res : (uint32_t)r;
}

/* Limits up front (memory_budget.h): the grid is fixed by the options and
 * the mesh's box, so the bake's peak is known before the tile map is made;
 * checked again once the split cells (S) are known, before the membership.
 *
 * Estimate (of allocations: calloc'd pages never written are not resident)
 * against peak RSS, `mesobake cells -i tests/data/spot_low_resolution.obj
 * -o o.meso -j 2 -v ...` under `/usr/bin/time -f %M` (2-core machine):
 *   --tile-res 32                 estimate  99 MiB   peak RSS  36 MiB
 *   --tile-res 128                estimate 238 MiB   peak RSS  87 MiB
 *   --tile-res 256                estimate 512 MiB   peak RSS 497 MiB
 *   --tiles 64 --tile-res 16      estimate 121 MiB   peak RSS  41 MiB
 *   --tiles 128 --tile-res 32     estimate 239 MiB   peak RSS  95 MiB
 *   --tiles 256 --tile-res 16     estimate 335 MiB   peak RSS 142 MiB
 * (96 MiB of each estimate is the program and its libraries). */
static meso_result check_budget(mesoi_bake_run* run, const meso_mesh* m, const meso_voxel_grid* g, uint32_t splits,
                                uint64_t* estimate, meso_error* err)
{
    uint64_t mixed = 0;
    const uint64_t need = meso_cells_estimate(m, g, splits, run->common.threads, &mixed);
    char n[32], b[32];
    *estimate = need;
    mesoi_run_stage(run, "memory estimate", run->fraction, run->fraction,
                    "memory estimate %s (%u split cells), budget %s",
                    meso_format_size(need, n, sizeof n), splits, meso_format_size(run->common.max_memory, b, sizeof b));
    return meso_budget_check(need, run->common.max_memory, MESO_LIMIT_ISSUE_REQUEST, err,
                             "cells: %u^3 voxels per tile, %ux%ux%u tiles (%llu of them near the surface)",
                             g->tile_res, g->tiles[0], g->tiles[1], g->tiles[2], (unsigned long long)mixed);
}

/* parity / vdb: refuse what parity would get wrong (it leaks through holes). */
static meso_result require_closed(const meso_mesh* m, const char* path, meso_error* err)
{
    meso_mesh_topology t;
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(m, lo, hi);
    meso_result r = meso_mesh_topology_compute(m, 1e-12 * diag * diag, &t, err);
    if (r != MESO_OK)
        return r;
    free(t.boundary);
    if (t.boundary_edges || t.nonmanifold_edges || t.misoriented_edges || t.duplicate_faces)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_VOXELIZE_ISSUE_MESH,
                              "%s: --voxelizer parity needs a closed, consistently oriented mesh (%u boundary, %u "
                              "non-manifold, %u misoriented edges, %u duplicate faces); use --voxelizer winding",
                              path, t.boundary_edges, t.nonmanifold_edges, t.misoriented_edges, t.duplicate_faces);
    return MESO_OK;
}

static mesoi_chunk typed_chunk(uint32_t type, uint32_t flags, uint16_t dtype, uint16_t comps, uint32_t d0, uint32_t d1,
                              uint32_t d2, const void* data, size_t size)
{
    return (mesoi_chunk){.desc = {.type = type, .flags = flags, .object = 1, .dtype = dtype, .components = comps,
                                 .dims = {d0, d1, d2}},
                        .data = data, .size = size};
}

/* CELL, TILE, SPLT, MEMB, NRMM and COLR of one level (FORMAT.md §7.2 kind
 * 3): level 0 at lod 0, a native level at its own lod. */
static void level_chunks(const meso_cells_chunks* cc, uint32_t R, uint32_t S, uint16_t lod, mesoi_chunk out[6])
{
    const uint32_t REQ = MESO_CHUNK_FLAG_REQUIRED;
    out[0] = typed_chunk(MESO_CHUNK_CELL, REQ, MESO_DTYPE_BYTES, 1, 1, 1, 1, cc->cell, sizeof cc->cell);
    out[1] = typed_chunk(MESO_CHUNK_TILE, REQ, cc->tile_dtype, 1, R, R, R, cc->tile, cc->tile_size);
    out[2] = typed_chunk(MESO_CHUNK_SPLT, REQ, MESO_DTYPE_U32, MESO_SPLT_COMPONENTS, S, 1, 1, cc->splt, cc->splt_size);
    out[3] = typed_chunk(MESO_CHUNK_MEMB, REQ, MESO_DTYPE_U32, 1, (uint32_t)(cc->memb_size / 4), 1, 1, cc->memb,
                         cc->memb_size);
    out[4] = typed_chunk(MESO_CHUNK_NRMM, 0, MESO_DTYPE_U16, 2, R, R, R, cc->nrmm, cc->nrmm_size);
    out[5] = typed_chunk(MESO_CHUNK_COLR, 0, MESO_DTYPE_U8, 4, R, R, R, cc->colr, cc->colr_size);
    for (int c = 0; c < 6; ++c)
        out[c].desc.lod = lod;
}

static void report_json(cJSON* rep, const meso_bake_cells_report* s)
{
    mesoi_report_fixes(rep, &s->fixes);
    cJSON_AddNumberToObject(rep, "tiles", (double)s->tiles);
    cJSON_AddNumberToObject(rep, "split_cells", s->split_cells);
    cJSON_AddNumberToObject(rep, "cells_inside", (double)s->cells_inside);
    cJSON_AddNumberToObject(rep, "cells_outside", (double)s->cells_outside);
    cJSON_AddNumberToObject(rep, "cells_intersected", (double)s->cells_intersected);
    cJSON_AddStringToObject(rep, "voxelizer", s->voxelizer);
    cJSON_AddNumberToObject(rep, "tile_res", s->tile_res);
    cJSON_AddNumberToObject(rep, "voxels_across", (double)s->voxels_across);
    cJSON_AddNumberToObject(rep, "cells_per_tile", s->cells_per_tile);
    cJSON_AddNumberToObject(rep, "wrapping_cells", s->wrapping_cells);
    cJSON_AddNumberToObject(rep, "wrapping_copies", (double)s->wrapping_copies);
    cJSON_AddNumberToObject(rep, "tiles_outside", (double)s->tiles_outside);
    cJSON_AddNumberToObject(rep, "tiles_inside", (double)s->tiles_inside);
    cJSON_AddNumberToObject(rep, "tiles_mixed", (double)s->tiles_mixed);
    cJSON_AddNumberToObject(rep, "membership_bytes", (double)s->membership_bytes);
    cJSON_AddNumberToObject(rep, "tile_map_bytes", (double)s->tile_map_bytes);
    cJSON_AddNumberToObject(rep, "normal_map_bytes", (double)s->normal_map_bytes);
    cJSON_AddNumberToObject(rep, "colour_map_bytes", (double)s->colour_map_bytes);
}

/* The file: META, RPRT, OBJT, then the base mesh and the cells chunks. */
/* "from-mesh[:G]": 1 with *g (default MESO_MESH_COLOUR_GRID_DEFAULT), 0 for
 * another SPEC, -1 for a bad G. */
static int from_mesh_spec(const char* spec, uint32_t* g)
{
    if (strncmp(spec, "from-mesh", 9) != 0 || (spec[9] != 0 && spec[9] != ':'))
        return 0;
    *g = MESO_MESH_COLOUR_GRID_DEFAULT;
    if (!spec[9])
        return 1;
    char* end = NULL;
    const unsigned long v = strtoul(spec + 10, &end, 10);
    if (spec[10] < '0' || spec[10] > '9' || *end || v < 2 || v > MESO_MESH_COLOUR_GRID_MAX)
        return -1;
    *g = (uint32_t)v;
    return 1;
}

/* The mesh's colour grid (--colour from-mesh): dims and sRGB RGBA8 texels. */
typedef struct colour_grid {
    uint32_t dims[3];
    uint8_t* rgba; /* NULL: none */
} colour_grid;

/* Native levels, at most MESO_CELLS_MAX_NATIVE, and none whose tile map
 * would be under MESO_CELLS_MIN_LEVEL_RES voxels per edge. */
enum { MESO_CELLS_MAX_NATIVE = 4, MESO_CELLS_MIN_LEVEL_RES = 4 };
_Static_assert(1 + MESO_CELLS_MAX_NATIVE + 1 <= MESOI_STANDIN_MAX_LEVELS, "room for the base mesh stand-in");

/* The native levels below level 0 (grid g, split cells sc, tags mb, tile
 * map tm, chunks cc, drawn surface f0), while each one's error stays below
 * the stand-in's e0; returns how many. Stored
 * errors must not decrease: a level measured closer than the one above it
 * is given that one's error (still a bound). */
static meso_result make_native(mesoi_bake_run* run, uint32_t want, const meso_voxel_grid* g,
                               const meso_split_cells* sc, const meso_membership* mb, const meso_tile_map* tm,
                               const meso_cells_chunks* cc, meso_cells_surface* f0, double e0, meso_cells_level* lv,
                               uint32_t* count, meso_error* err)
{
    *count = 0;
    for (uint32_t k = 0; k < want; ++k) {
        const meso_voxel_grid* fg = k ? &lv[k - 1].g : g;
        if (fg->tile_res % 2 || fg->tile_res / 2 < MESO_CELLS_MIN_LEVEL_RES)
            break;
        const double t = meso_seconds();
        meso_result r = meso_cells_level_build(f0, fg, k ? &lv[k - 1].tm : tm, k ? &lv[k - 1].sc : sc,
                                               k ? &lv[k - 1].mb : mb, k ? &lv[k - 1].cc : cc, run->common.threads,
                                               &lv[k], err);
        if (r != MESO_OK)
            return r;
        if (k && lv[k].error.bound < lv[k - 1].error.bound)
            lv[k].error.bound = lv[k - 1].error.bound;
        mesoi_run_stage(run, "levels", 0.95, 0.95,
                        "native level %u: %u^3 voxels a tile, %u split cells, within %g of level 0 (stand-in: %g) "
                        "(%.0f ms)",
                        k + 1, lv[k].g.tile_res, lv[k].sc.split_count, lv[k].error.bound, e0,
                        1e3 * (meso_seconds() - t));
        if (!(lv[k].error.bound < e0)) { /* the base mesh is as close: no use */
            meso_cells_level_free(&lv[k]);
            break;
        }
        *count = k + 1;
    }
    return MESO_OK;
}

static meso_result make_levels(mesoi_bake_run* run, const meso_bake_cells_options* a, const meso_mesh* m,
                               const meso_voxel_grid* g, const meso_split_cells* sc, const meso_membership* mb,
                               const meso_tile_map* tm, const meso_cells_chunks* cc, const colour_grid* cg,
                               mesoi_standin_levels* out, meso_cells_level* native, meso_bake_cells_report* s,
                               meso_error* err)
{
    memset(out, 0, sizeof *out);
    if (a->levels == 1)
        return MESO_OK;
    const double t = meso_seconds();
    meso_cells_standin_error se;
    meso_cells_surface* f0 = NULL; /* level 0's faces: every level is measured against them */
    meso_result r = meso_cells_surface_build(m, g, sc, mb, &f0, err);
    if (r == MESO_OK)
        r = meso_cells_standin_measure(m, f0, run->common.threads, &se, err);
    if (r != MESO_OK) {
        meso_cells_surface_free(f0);
        return r;
    }
    s->surface_faces = se.faces;
    if (se.too_many || !isfinite(se.bound) || !(se.bound < 1e30)) {
        if (se.too_many)
            mesoi_run_warning(run, 0,
                              "the cells draw more than %u voxel faces: the stand-in's error is not measured, so no "
                              "levels (--levels 1 asks for none)",
                              MESO_CELLS_STANDIN_MAX_FACES);
        else
            mesoi_run_warning(run, 0, "no cell is inside the mesh: nothing drawn, so no stand-in level");
        meso_cells_surface_free(f0);
        return MESO_OK;
    }
#if !MESO_HAVE_MESHOPTIMIZER
    if (a->levels == 0)
        mesoi_run_warning(run, 0, "built without meshoptimizer: the base mesh is the only stand-in");
#endif
    const uint32_t want = mesoi_native_wanted(a->levels, MESO_CELLS_MAX_NATIVE);
    uint32_t nn = 0;
    r = make_native(run, want, g, sc, mb, tm, cc, f0, se.bound, native, &nn, err);
    if (r == MESO_OK) /* the rest for the stand-ins: at most MAX levels in all (auto), or --levels */
        r = mesoi_standin_levels_build(m, se.bound, (a->levels ? a->levels : (int)MESOI_STANDIN_MAX_LEVELS) - (int)nn,
                                       run->common.threads, out, err);
    /* Their colours: what the voxel faces show (FORMAT.md §7.3 VCOL),
     * sampled half a voxel apart where a triangle is small enough, at most
     * 2 x 2 sub-triangles a triangle (cells_standin.c says why). */
    const double tv = meso_seconds();
    meso_cells_colours colours = {.colr = cc->colr, .grid = cg->rgba};
    memcpy(colours.grid_dims, cg->dims, sizeof colours.grid_dims);
    for (int k = 0; k < 3; ++k) {
        colours.origin[k] = g->origin[k];
        colours.extent[k] = (double)g->tiles[k] * g->tile_res * g->voxel_size;
    }
    mesoi_appearance shows;
    if (r == MESO_OK && meso_cells_surface_appearance(f0, &colours, &shows))
        r = mesoi_standin_levels_appearance(out, m, 0.5 * g->voxel_size, &shows, run->common.threads, err);
    meso_cells_surface_free(f0);
    if (r != MESO_OK)
        return r;
    const double colour_ms = 1e3 * (meso_seconds() - tv);
    out->native = nn;
    for (uint32_t k = 0; k < nn; ++k)
        out->native_error[k] = native[k].error.bound;
    mesoi_run_stage(run, "levels", 0.97, 0.97,
                    "stand-in: base mesh within %g of the %llu voxel faces drawn (sampled %g, radius %g); %u "
                    "simplified levels, their colours in %.0f ms (%.0f ms in all)",
                    se.bound, (unsigned long long)se.faces, se.sampled, se.radius, out->chain_count, colour_ms,
                    1e3 * (meso_seconds() - t));
    return MESO_OK;
}

static meso_result assemble(const meso_bake_cells_options* a, const meso_mesh* m, const meso_voxel_grid* g,
                            uint32_t R, const meso_split_cells* sc, const meso_cells_chunks* cc,
                            const colour_grid* cg, mesoi_standin_levels* lv, const meso_cells_level* native,
                            meso_bake_cells_report* s, meso_bake_output** out, meso_error* err)
{
    meso_mesh_chunk mesh_chunk = {0};
    meso_result r = meso_bake_mesh_chunk(m, NULL, &mesh_chunk, err);
    if (r != MESO_OK)
        return r;
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_CELLS};
    for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = (float)g->origin[k];
        rec.bbox_max[k] = (float)(g->origin[k] + (double)g->tiles[k] * R * g->voxel_size);
    }
    snprintf(rec.name, sizeof(rec.name), "%s", mesoi_input_label(a->input));
    cJSON* meta = mesoi_meta_new("cells");
    cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
    cJSON_AddStringToObject(params, "tile_map", a->tile_map);
    cJSON_AddNumberToObject(params, "tile_res", R);
    cJSON_AddNumberToObject(params, "tiles", g->tiles[0]);
    cJSON_AddStringToObject(params, "colour", a->colour);
    cJSON_AddStringToObject(params, "voxelizer", a->voxelizer);
    if (a->levels != 1) /* --levels 1 keeps the META of earlier versions */
        cJSON_AddNumberToObject(params, "levels", a->levels);
    r = mesoi_add_provenance(cJSON_AddArrayToObject(meta, "inputs"), a->input, a->mesh, err);
    cJSON* rep = cJSON_CreateObject();
    report_json(rep, s);

    const uint32_t REQ = MESO_CHUNK_FLAG_REQUIRED;
    mesoi_chunk chunks[8 + 6 * MESO_CELLS_MAX_NATIVE + 2 * MESOI_STANDIN_MAX_LEVELS + 1]; /* stand-ins: MESH and VCOL each */
    chunks[0] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_MESH, .flags = REQ, .object = 1,
                                       .encoding = mesh_chunk.encoding, .decoded_size = mesh_chunk.decoded_size},
                              .data = mesh_chunk.data, .size = mesh_chunk.size};
    level_chunks(cc, R, sc->split_count, 0, chunks + 1);
    int count = 7;
    /* Native levels (cells_levels.h): their own cells chunks at lod 1..N;
     * their MESH resolves to the base mesh stand-in's at lod N + 1. */
    for (uint32_t k = 0; k < lv->native; ++k) {
        level_chunks(&native[k].cc, native[k].g.tile_res, native[k].sc.split_count, (uint16_t)(k + 1),
                     chunks + count);
        count += 6;
    }
    if (cg->rgba) { /* the mesh's base colour (FORMAT.md 7.2 kind 3): replaces COLR's as the albedo */
        chunks[count] = typed_chunk(MESO_CHUNK_TX3D, 0, MESO_DTYPE_U8, 4, cg->dims[0], cg->dims[1], cg->dims[2],
                                    cg->rgba, 4 * (size_t)cg->dims[0] * cg->dims[1] * cg->dims[2]);
        chunks[count++].desc.lod = (uint16_t)lv->native; /* one copy, which every native level resolves to */
    }
    /* The stand-ins (FORMAT.md §7.10 form MESH): the base mesh's bytes again
     * at lod N + 1, the simplified meshes at lod N + 2.., and the LODS
     * records. */
    s->level_count = 1;
    s->level_triangles[0] = m->triangle_count;
    if (lv->count) {
        count += (int)mesoi_standin_levels_append(lv, m, &chunks[0], rec.bbox_min, rec.bbox_max, chunks + count, rep);
        for (uint32_t L = 1; L <= lv->native + lv->count; ++L) {
            s->level_error[L] = lv->error[L];
            s->level_triangles[L] = lv->triangles[L];
        }
        cJSON_AddNumberToObject(rep, "surface_faces", (double)s->surface_faces);
        /* How each native level's error was bounded (cells_standin.c): on
         * the clipped surfaces, or chained where those were not measured. */
        cJSON* jl = cJSON_GetObjectItemCaseSensitive(rep, "levels");
        for (uint32_t k = 0; k < lv->native; ++k)
            cJSON_AddStringToObject(cJSON_GetArrayItem(jl, (int)k + 1), "error_bound",
                                    isfinite(native[k].error.clipped) ? "clipped" : "chained");
        s->level_count = 1 + lv->native + lv->count;
        s->native_levels = lv->native;
    }
    if (r == MESO_OK)
        r = mesoi_output_build(meta, rep, &rec, chunks, count, out, err);
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    free(mesh_chunk.data);
    return r;
}

meso_result meso_bake_cells(const meso_bake_cells_options* o, meso_bake_output** out, meso_bake_cells_report* report,
                            meso_error* err)
{
    if (!o || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "meso_bake_cells: NULL options or output");
    *out = NULL;
    meso_bake_cells_options opts = *o;
    meso_bake_cells_options* a = &opts;
    if (!a->tile_map)
        a->tile_map = "voronoi";
    if (!a->colour)
        a->colour = "hash";
    if (!a->voxelizer)
        a->voxelizer = "auto";
    if (strcmp(a->voxelizer, "auto") && strcmp(a->voxelizer, "vdb") && strcmp(a->voxelizer, "parity") &&
        strcmp(a->voxelizer, "winding"))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "voxelizer '%s': expected auto, vdb, parity or winding",
                              a->voxelizer);
    if (a->tiles > MESO_BAKE_MAX_TILES || a->tile_res > MESO_BAKE_MAX_TILE_RES || (a->tiles && a->cell_size > 0) ||
        !(a->cell_size >= 0 && a->cell_size < 1e30) || a->levels < 0 || a->levels > (int)MESO_BAKE_CELLS_MAX_LEVELS)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                              "cells options: tiles 0..16384 or cell_size > 0 (not both), tile_res 0..1024, levels 0..%u",
                              MESO_BAKE_CELLS_MAX_LEVELS);
    meso_bake_cells_report rep_local;
    meso_bake_cells_report* s = report ? report : &rep_local;
    memset(s, 0, sizeof(*s));
    mesoi_bake_run run;
    mesoi_run_begin(&run, &a->common);
    const int threads = run.common.threads;
    meso_mesh m = {0};
    meso_tile_map tm = {0};
    meso_split_cells sc = {0};
    meso_voxel_grid g = {0};
    meso_membership mb = {0};
    meso_cells_chunks cc = {0};
    uint32_t R = a->tile_res;
    const meso_voxelizer method = !strcmp(a->voxelizer, "winding") ? MESO_VOXELIZE_WINDING
                                  : !strcmp(a->voxelizer, "auto")  ? MESO_VOXELIZE_AUTO
                                                                   : MESO_VOXELIZE_PARITY;
    meso_mesh_materials mats = {0};
    colour_grid cg = {{0, 0, 0}, NULL};
    uint32_t cg_res = 0;
    const int from_mesh = from_mesh_spec(a->colour, &cg_res);
    if (from_mesh < 0)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_CELLS_ISSUE_COLOUR_SPEC,
                              "--colour '%s': from-mesh:G takes G in 2..%u (samples along the longest side)", a->colour,
                              MESO_MESH_COLOUR_GRID_MAX);
    if (from_mesh && !a->input)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_MESH_COLOUR_ISSUE_NONE,
                              "--colour from-mesh needs an input file (a glTF with a base colour)");
    meso_result r = from_mesh ? mesoi_load_mesh_materials(&run, a->input, &m, &mats, &s->fixes, err)
                              : mesoi_load_input(&run, a->input, a->mesh, &m, &s->fixes, err);
    if (r == MESO_OK && method == MESO_VOXELIZE_PARITY)
        r = require_closed(&m, a->input ? a->input : MESOI_MEMORY_INPUT, err);
    if (r == MESO_OK)
        r = make_grid(a, &m, planned_res(a), &g, err);
    if (r == MESO_OK)
        r = check_budget(&run, &m, &g, 1, &s->memory_estimate, err);
    double t = meso_seconds();
    if (r == MESO_OK)
        r = make_tile_map(a, &R, &tm, err);
    if (r == MESO_OK)
        r = meso_split_cells_compute(&tm, threads, &sc, err);
    if (r == MESO_OK)
        mesoi_run_stage(&run, "tile map", 0.2, 0.2,
                        "tile map %s, R = %u: %u cells, %u split cells (%u wrapping cells) (%.0f ms)", a->tile_map, R,
                        sc.cell_count, sc.split_count, sc.wrapping_cells, 1e3 * (meso_seconds() - t));
    if (r == MESO_OK && sc.split_count == 0)
        r = meso_bake_fail(err, tm.kind == MESO_TILE_MAP_RAW ? MESO_ERR_CORRUPT : MESO_ERR_INVALID_ARG,
                           MESO_TILEMAP_ISSUE_CONTENT, "--tile-map '%s': the tile map has no cells (every voxel is 0)",
                           a->tile_map); /* a file of zeros is an invalid input (3), a generated one a bad option (1) */
    if (r == MESO_OK && R != g.tile_res) /* planned_res and make_tile_map disagree: a bug */
        r = meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "cells: tile resolution %u, planned %u", R, g.tile_res);
    if (r == MESO_OK)
        r = check_budget(&run, &m, &g, sc.split_count, &s->memory_estimate, err);
    if (r == MESO_OK)
        r = meso_membership_compute(&m, &g, &sc, method, threads, &mb, err);
    if (r == MESO_OK)
        mesoi_run_stage(&run, "membership", 0.7, 0.7,
                        "%ux%ux%u tiles, %u voxels across, %s: %llu rays; cells %llu inside, %llu outside, %llu "
                        "intersected; tiles %llu outside, %llu inside, %llu mixed (%.0f ms)",
                        g.tiles[0], g.tiles[1], g.tiles[2], g.tiles[0] * R, meso_voxelizer_name(mb.voxelize.method),
                        (unsigned long long)mb.voxelize.rows, (unsigned long long)mb.cells_inside,
                        (unsigned long long)mb.cells_outside, (unsigned long long)mb.cells_intersected,
                        (unsigned long long)mb.tiles_outside, (unsigned long long)mb.tiles_inside,
                        (unsigned long long)mb.tiles_mixed, 1e3 * mb.seconds);
    t = meso_seconds();
    if (r == MESO_OK)
        r = meso_cells_chunks_build(&tm, &sc, &mb, g.origin, g.voxel_size, from_mesh ? "hash" : a->colour, threads,
                                    &cc, err);
    if (r == MESO_OK && from_mesh) {
        double ext[3];
        for (int k = 0; k < 3; ++k)
            ext[k] = (double)g.tiles[k] * R * g.voxel_size;
        meso_mesh_colour_grid_dims(ext, cg_res, cg.dims);
        cg.rgba = malloc(4 * (size_t)cg.dims[0] * cg.dims[1] * cg.dims[2]);
        r = cg.rgba ? meso_mesh_colour_grid_build(&m, &mats, g.origin, ext, cg.dims, cg.rgba, err)
                    : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "colour grid: out of memory");
        if (r == MESO_OK)
            mesoi_run_stage(&run, "colour grid", 0.95, 0.95, "mesh colour grid %ux%ux%u", cg.dims[0], cg.dims[1],
                            cg.dims[2]);
    }
    if (r == MESO_OK)
        mesoi_run_stage(&run, "normal and colour maps", 0.9, 0.9,
                        "normal and colour maps: %llu border voxels of %u^3 (%.0f ms)",
                        (unsigned long long)cc.border_voxels, R, 1e3 * (meso_seconds() - t));
    if (r == MESO_OK) {
        s->tiles = mb.tile_count;
        memcpy(s->tiles_per_axis, g.tiles, sizeof(s->tiles_per_axis));
        s->tile_res = R;
        s->split_cells = sc.split_count;
        s->cells_per_tile = sc.cell_count;
        s->wrapping_cells = sc.wrapping_cells;
        s->cells_inside = mb.cells_inside;
        s->cells_outside = mb.cells_outside;
        s->cells_intersected = mb.cells_intersected;
        s->wrapping_copies = mb.wrapping_copies;
        s->tiles_outside = mb.tiles_outside;
        s->tiles_inside = mb.tiles_inside;
        s->tiles_mixed = mb.tiles_mixed;
        s->voxels_across = (uint64_t)g.tiles[0] * R;
        s->voxelizer = meso_voxelizer_name(mb.voxelize.method);
        s->membership_bytes = cc.memb_size;
        s->tile_map_bytes = cc.tile_size;
        s->normal_map_bytes = cc.nrmm_size;
        s->colour_map_bytes = cc.colr_size;
    }
    mesoi_standin_levels lv = {0};
    meso_cells_level native[MESO_CELLS_MAX_NATIVE];
    memset(native, 0, sizeof native);
    if (r == MESO_OK)
        r = make_levels(&run, a, &m, &g, &sc, &mb, &tm, &cc, &cg, &lv, native, s, err);
    if (r == MESO_OK)
        r = assemble(a, &m, &g, R, &sc, &cc, &cg, &lv, native, s, out, err);
    for (int k = 0; k < MESO_CELLS_MAX_NATIVE; ++k)
        meso_cells_level_free(&native[k]);
    mesoi_standin_levels_free(&lv);
    meso_cells_chunks_free(&cc);
    free(cg.rgba);
    meso_mesh_materials_free(&mats);
    meso_membership_free(&mb);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&tm);
    meso_mesh_free(&m);
    if (r == MESO_OK)
        mesoi_run_done(&run);
    return r;
}
