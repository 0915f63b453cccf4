/*
 * rt_cells_skip.c — empty-space skipping inside MIXED tiles for the cells
 * ray tracer (cell-based-object-representation.md §3.2.2 skips whole
 * OUTSIDE tiles; this is the same idea one level down).
 *
 * Inside one tile a voxel's state (SOLID or not) depends only on its split
 * id: the tile's membership record tags whole split cells. So a cube of
 * voxels that all share v's id, all in v's tile, is all of v's state, and a
 * search that is in v and not done there may leave the cube in one step,
 * exactly where the voxel walk would have left it (shaders/cells_frag.glsl
 * does so as it crosses whole tiles). The tiles all repeat one tile map, so
 * the radii are the map's, computed once when a level is loaded.
 *
 * The radius. Let B be the voxels with a 26-neighbour (in the tile) of
 * another id, and D(v) the Chebyshev distance from v to the nearest voxel
 * of another id. For v outside B the voxel next to that nearest one on the
 * way to v is in B at D - 1, and any voxel of B nearer than D - 1 would
 * have a neighbour of another id nearer than D; so the largest uniform cube
 * around v has radius D - 1 = the Chebyshev distance from v to B (0 on B).
 * That distance is separable (one pass per axis of min over j of
 * max(|i - j|, f(j)), cut off at the cap), then clipped by the distance to
 * the tile's faces (the next tile has its own record). test_cells_skip
 * checks the radii against the cube grown voxel by voxel.
 *
 * Stored above the ids: TILE values are split ids 0..S. With S < 2^11 in a
 * u16 map (2^27 in a u32 map) the top five bits are free and hold the
 * radius, capped at 31; otherwise nothing is packed and the shader walks
 * voxel by voxel as before. Decided here rather than baked so files
 * written before it draw as fast, and the format is unchanged.
 */
#include "rt_cells_skip.h"

#include "file_internal.h"

#include <string.h>

int mesoi_cells_skipping = 1;

/* f(i) = min over j of max(|i - j|, f(j)) along one line of n values. */
static void chebyshev_line(uint8_t* line, uint32_t n, size_t stride, uint8_t* tmp)
{
    for (uint32_t i = 0; i < n; ++i)
        tmp[i] = line[i * stride];
    for (uint32_t i = 0; i < n; ++i) {
        uint32_t best = tmp[i];
        for (uint32_t d = 1; d < best; ++d) {
            if (i >= d && (tmp[i - d] > d ? tmp[i - d] : d) < best)
                best = tmp[i - d] > d ? tmp[i - d] : d;
            if (i + d < n && (tmp[i + d] > d ? tmp[i + d] : d) < best)
                best = tmp[i + d] > d ? tmp[i + d] : d;
        }
        line[i * stride] = (uint8_t)best;
    }
}

void mesoi_cells_skip_radii(const uint32_t* ids, uint32_t res, uint8_t* radius)
{
    const uint32_t R = res;
    const size_t n = (size_t)R * R * R;
    const uint8_t far = MESOI_CELLS_SKIP_MAX + 1;
    memset(radius, far, n);
    /* B: each pair of 26-neighbours once (the 13 offsets with a positive
     * first non-zero component), both marked when their ids differ. */
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                const size_t v = x + (size_t)R * (y + (size_t)R * z);
                for (int dz = 0; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            if (dz == 0 && (dy < 0 || (dy == 0 && dx <= 0)))
                                continue;
                            const int64_t wx = (int64_t)x + dx, wy = (int64_t)y + dy, wz = (int64_t)z + dz;
                            if (wx < 0 || wy < 0 || wx >= R || wy >= R || wz >= R)
                                continue;
                            const size_t w = (size_t)wx + (size_t)R * ((size_t)wy + (size_t)R * (size_t)wz);
                            if (ids[v] != ids[w])
                                radius[v] = radius[w] = 0;
                        }
            }
    uint8_t tmp[MESOI_CELLS_SKIP_RES];
    const size_t stride[3] = {1, R, (size_t)R * R};
    for (int a = 0; a < 3; ++a) /* each line along axis a */
        for (uint32_t q = 0; q < R; ++q)
            for (uint32_t p = 0; p < R; ++p)
                chebyshev_line(radius + p * stride[(a + 1) % 3] + q * stride[(a + 2) % 3], R, stride[a], tmp);
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                uint32_t r = radius[x + (size_t)R * (y + (size_t)R * z)];
                const uint32_t edge[6] = {x, R - 1 - x, y, R - 1 - y, z, R - 1 - z};
                for (int k = 0; k < 6; ++k)
                    r = edge[k] < r ? edge[k] : r;
                r = r > MESOI_CELLS_SKIP_MAX ? MESOI_CELLS_SKIP_MAX : r;
                radius[x + (size_t)R * (y + (size_t)R * z)] = (uint8_t)r;
            }
}

size_t mesoi_cells_skip_scratch(uint32_t res)
{
    return res > MESOI_CELLS_SKIP_RES ? 0 : (size_t)res * res * res * (sizeof(uint32_t) + 1);
}

int mesoi_cells_skip_pack(uint8_t* tile, int wide, uint32_t res, void* scratch)
{
    const int id_bits = wide ? 27 : 11;
    if (res == 0 || res > MESOI_CELLS_SKIP_RES)
        return 0;
    const size_t n = (size_t)res * res * res;
    uint32_t* ids = scratch;
    uint8_t* radius = (uint8_t*)(ids + n);
    for (size_t v = 0; v < n; ++v) {
        ids[v] = wide ? mesoi_ld32(tile + 4 * v) : mesoi_ld16(tile + 2 * v);
        if (ids[v] >= (1u << id_bits)) /* S too large to leave the bits free */
            return 0;
    }
    mesoi_cells_skip_radii(ids, res, radius);
    for (size_t v = 0; v < n; ++v) {
        if (wide)
            mesoi_st32(tile + 4 * v, ids[v] | (uint32_t)radius[v] << id_bits);
        else
            mesoi_st16(tile + 2 * v, (uint16_t)(ids[v] | (uint32_t)radius[v] << id_bits));
    }
    return id_bits;
}

int mesoi_cells_skip_level(const meso_file* f, uint32_t object, uint16_t lod, uint8_t* tile,
                           const meso_allocator* alloc)
{
    const int32_t i = meso_file_find_level(f, MESO_CHUNK_TILE, object, lod); /* as the loader finds it */
    if (i < 0 || !tile || !mesoi_cells_skipping)
        return 0;
    const meso_chunk_info* c = meso_file_chunk(f, (uint32_t)i);
    const uint32_t R = c->dims[0];
    const size_t size = c->dims[1] == R && c->dims[2] == R ? mesoi_cells_skip_scratch(R) : 0;
    void* scratch = size ? alloc->alloc_fn(size, alloc->user) : NULL;
    if (!scratch) /* no radii: the walk goes voxel by voxel */
        return 0;
    const int bits = mesoi_cells_skip_pack(tile, c->dtype == MESO_DTYPE_U32, R, scratch);
    alloc->free_fn(scratch, alloc->user);
    return bits;
}
