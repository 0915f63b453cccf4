/*
 * cells_levels.c — see cells_levels.h.
 */
#include "cells_levels.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "srgb.h"

/* Fine voxel c (0..7: x, y, z bits) of coarse voxel (x, y, z), in a fine
 * map of R^3. */
static inline size_t child(uint32_t R, uint32_t x, uint32_t y, uint32_t z, int c)
{
    return (2 * x + (uint32_t)(c & 1)) + (size_t)R * ((2 * y + (uint32_t)(c >> 1 & 1)) + (size_t)R * (2 * z + (uint32_t)(c >> 2)));
}

meso_result meso_tile_map_halve(const meso_tile_map* fine, meso_tile_map* out, meso_error* err)
{
    memset(out, 0, sizeof *out);
    const uint32_t R = fine->res, H = R / 2;
    if (R < 2 || R % 2)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "cells level: a %u^3 tile map cannot be halved", R);
    out->cells = malloc(sizeof(uint16_t) * (size_t)H * H * H);
    if (!out->cells)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "cells level: out of memory");
    out->kind = MESO_TILE_MAP_RAW;
    out->res = H;
    out->cell_count = fine->cell_count;
    for (uint32_t z = 0; z < H; ++z)
        for (uint32_t y = 0; y < H; ++y)
            for (uint32_t x = 0; x < H; ++x) {
                uint16_t v[8];
                for (int c = 0; c < 8; ++c)
                    v[c] = fine->cells[child(R, x, y, z, c)];
                uint16_t best = 0;
                int best_n = 0;
                for (int c = 0; c < 8; ++c) {
                    int n = 0;
                    for (int d = 0; d < 8; ++d)
                        n += v[d] == v[c];
                    if (n > best_n || (n == best_n && v[c] < best)) {
                        best = v[c];
                        best_n = n;
                    }
                }
                out->cells[x + (size_t)H * (y + (size_t)H * z)] = best;
            }
    return MESO_OK;
}

void meso_cells_colours_halve(const meso_tile_map* fine, const uint8_t* fine_rgba, const meso_tile_map* coarse,
                              uint8_t* out)
{
    const uint32_t R = fine->res, H = coarse->res;
    for (uint32_t z = 0; z < H; ++z)
        for (uint32_t y = 0; y < H; ++y)
            for (uint32_t x = 0; x < H; ++x) {
                const size_t o = x + (size_t)H * (y + (size_t)H * z);
                const uint16_t idx = coarse->cells[o];
                uint8_t* p = out + 4 * o;
                memset(p, 0, 4);
                if (!idx)
                    continue;
                double sum[4] = {0, 0, 0, 0};
                int n = 0;
                for (int c = 0; c < 8; ++c) {
                    const size_t f = child(R, x, y, z, c);
                    if (fine->cells[f] != idx)
                        continue;
                    for (int k = 0; k < 3; ++k)
                        sum[k] += meso_srgb_to_linear(fine_rgba[4 * f + (size_t)k] / 255.0);
                    sum[3] += fine_rgba[4 * f + 3];
                    ++n;
                }
                for (int k = 0; k < 3; ++k)
                    p[k] = (uint8_t)lround(255.0 * meso_linear_to_srgb(sum[k] / n));
                p[3] = (uint8_t)lround(sum[3] / n);
            }
}

/* The coarse level's voxels as a voxelization (meso_voxels), from the
 * finer level's drawn solid instead of the mesh: a coarse voxel is inside
 * when a fine voxel of its block that holds its index is SOLID at the
 * finer level (its split cell tagged INSIDE in that tile). */
static meso_result inherit_voxels(const meso_tile_map* ftm, const meso_split_cells* fsc, const meso_membership* fmb,
                                  const meso_voxel_grid* cg, const meso_tile_map* ctm, meso_voxels* out,
                                  meso_error* err)
{
    memset(out, 0, sizeof *out);
    out->grid = *cg;
    const uint32_t R = ftm->res, H = ctm->res, S = fsc->split_count;
    const uint64_t T = (uint64_t)cg->tiles[0] * cg->tiles[1] * cg->tiles[2], W = meso_voxel_tile_words(H);
    out->tile_words = W;
    out->tile_class = malloc(T ? T : 1);
    uint64_t* bits = malloc(sizeof(uint64_t) * W);
    uint8_t* tag = malloc((size_t)S + 1);
    uint64_t cap = 0;
    meso_result r = out->tile_class && bits && tag ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    for (uint64_t t = 0; r == MESO_OK && t < T; ++t) {
        const uint32_t tx = (uint32_t)(t % cg->tiles[0]), ty = (uint32_t)(t / cg->tiles[0] % cg->tiles[1]),
                       tz = (uint32_t)(t / cg->tiles[0] / cg->tiles[1]);
        tag[0] = 0;
        for (uint32_t sp = 1; sp <= S; ++sp)
            tag[sp] = meso_membership_get(fmb, tx, ty, tz, sp) == MESO_MEMB_INSIDE;
        memset(bits, 0, sizeof(uint64_t) * W);
        uint64_t ones = 0;
        for (uint32_t z = 0; z < H; ++z)
            for (uint32_t y = 0; y < H; ++y)
                for (uint32_t x = 0; x < H; ++x) {
                    const uint64_t v = x + (uint64_t)H * (y + (uint64_t)H * z);
                    const uint16_t idx = ctm->cells[v];
                    int in = 0;
                    for (int c = 0; idx && c < 8 && !in; ++c) {
                        const size_t f = child(R, x, y, z, c);
                        in = ftm->cells[f] == idx && tag[fsc->voxel_split[f]];
                    }
                    if (in) {
                        bits[v / 64] |= 1ull << (v % 64);
                        ++ones;
                    }
                }
        const uint64_t n = (uint64_t)H * H * H;
        out->tile_class[t] = ones == 0 ? MESO_TILE_OUTSIDE : ones == n ? MESO_TILE_INSIDE : MESO_TILE_MIXED;
        if (out->tile_class[t] != MESO_TILE_MIXED)
            continue;
        if (out->mixed_count == cap) {
            cap = cap ? 2 * cap : 64;
            uint64_t* ids = realloc(out->mixed_tiles, sizeof(uint64_t) * cap);
            if (ids)
                out->mixed_tiles = ids;
            uint64_t* b = realloc(out->bits, sizeof(uint64_t) * W * cap);
            if (b)
                out->bits = b;
            if (!ids || !b) {
                r = MESO_ERR_OUT_OF_MEMORY;
                break;
            }
        }
        out->mixed_tiles[out->mixed_count] = t;
        memcpy(out->bits + W * out->mixed_count++, bits, sizeof(uint64_t) * W);
    }
    free(bits);
    free(tag);
    if (r != MESO_OK) {
        meso_voxels_free(out);
        return meso_bake_fail(err, r, 0, "cells level: out of memory");
    }
    return MESO_OK;
}

meso_result meso_cells_level_build(meso_cells_surface* f0, const meso_voxel_grid* finer_g, const meso_tile_map* finer_tm,
                                   const meso_split_cells* finer_sc, const meso_membership* finer_mb,
                                   const meso_cells_chunks* finer_cc, int threads, meso_cells_level* out,
                                   meso_error* err)
{
    memset(out, 0, sizeof *out);
    out->g = *finer_g;
    out->g.tile_res = finer_g->tile_res / 2;
    out->g.voxel_size = 2.0 * finer_g->voxel_size; /* exact: an f32 value doubled */
    meso_voxels vox = {0};
    meso_result r = meso_tile_map_halve(finer_tm, &out->tm, err);
    if (r == MESO_OK)
        r = meso_split_cells_compute(&out->tm, threads, &out->sc, err);
    if (r == MESO_OK && out->sc.split_count == 0) { /* halving erased every cell: no such level */
        out->error.bound = INFINITY;
        return MESO_OK;
    }
    if (r == MESO_OK)
        r = inherit_voxels(finer_tm, finer_sc, finer_mb, &out->g, &out->tm, &vox, err);
    if (r == MESO_OK)
        r = meso_membership_from_voxels(&vox, &out->sc, threads, &out->mb, err);
    meso_voxels_free(&vox);
    if (r == MESO_OK) /* "hash" only fills COLR, replaced below by the prefiltered colours */
        r = meso_cells_chunks_build(&out->tm, &out->sc, &out->mb, out->g.origin, out->g.voxel_size, "hash", threads,
                                    &out->cc, err);
    if (r == MESO_OK)
        meso_cells_colours_halve(finer_tm, finer_cc->colr, &out->tm, out->cc.colr);
    if (r == MESO_OK)
        r = meso_cells_level_measure(f0, &out->g, &out->sc, &out->mb, threads, &out->error, err);
    if (r != MESO_OK)
        meso_cells_level_free(out);
    return r;
}

void meso_cells_level_free(meso_cells_level* l)
{
    meso_cells_chunks_free(&l->cc);
    meso_membership_free(&l->mb);
    meso_split_cells_free(&l->sc);
    meso_tile_map_free(&l->tm);
    memset(l, 0, sizeof *l);
}
