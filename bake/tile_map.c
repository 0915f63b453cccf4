/*
 * tile_map.c — periodic Voronoi and sphere tile maps, raw tile-map files.
 * See tile_map.h for the construction and why it is exact.
 */
#include "tile_map.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"
#include "memory_budget.h"

uint64_t meso_splitmix64(uint64_t* state)
{
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Lattice points per tile edge. */
static uint64_t period(uint32_t res)
{
    return 2ull * res * MESO_TILE_MAP_SUBSTEPS;
}

/* Squared torus distance along one axis between lattice coordinates a (any
 * integer) and b in [0, m). */
static uint64_t axis_sq(int64_t a, int64_t b, int64_t m)
{
    int64_t d = (a - b) % m;
    if (d < 0)
        d += m;
    if (d > m - d)
        d = m - d;
    return (uint64_t)d * (uint64_t)d;
}

/* Nearest seed (1-based; ties to the lower index) of the point p and its
 * squared distance. */
static uint16_t nearest(const meso_tile_map* m, const int64_t p[3], uint64_t* best_sq)
{
    const int64_t M = (int64_t)period(m->res);
    uint64_t best = UINT64_MAX;
    uint16_t idx = 0;
    for (uint32_t k = 0; k < m->cell_count; ++k) {
        const uint32_t* s = m->seeds + 3 * (size_t)k;
        const uint64_t d = axis_sq(p[0], s[0], M) + axis_sq(p[1], s[1], M) + axis_sq(p[2], s[2], M);
        if (d < best) {
            best = d;
            idx = (uint16_t)(k + 1);
        }
    }
    *best_sq = best;
    return idx;
}

uint16_t meso_tile_map_eval(const meso_tile_map* m, int64_t x, int64_t y, int64_t z)
{
    const int64_t R = m->res;
    if (m->kind == MESO_TILE_MAP_RAW || !m->seeds) {
        x = ((x % R) + R) % R;
        y = ((y % R) + R) % R;
        z = ((z % R) + R) % R;
        return m->cells[(size_t)x + (size_t)R * ((size_t)y + (size_t)R * (size_t)z)];
    }
    const int64_t S = MESO_TILE_MAP_SUBSTEPS;
    const int64_t p[3] = {(2 * x + 1) * S, (2 * y + 1) * S, (2 * z + 1) * S};
    uint64_t d;
    const uint16_t idx = nearest(m, p, &d);
    return (m->kind == MESO_TILE_MAP_SPHERES && d > m->radius_sq) ? 0 : idx;
}

void meso_tile_map_free(meso_tile_map* m)
{
    if (!m)
        return;
    free(m->cells);
    free(m->seeds);
    memset(m, 0, sizeof(*m));
}

/* >>generate ------------------------------------------------------------------
 * One line of voxels (fixed y, z) at a time: the y and z parts of every
 * seed's squared distance are summed once per line, leaving one axis_sq and
 * one add per seed and voxel. Lines are independent, so the OpenMP split does
 * not change the result. */
meso_result meso_tile_map_generate(const meso_tile_map_params* p, int threads, meso_tile_map* out,
                                   meso_error* err)
{
    if (!p || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "tile map: NULL argument");
    memset(out, 0, sizeof(*out));
    if (p->kind != MESO_TILE_MAP_VORONOI && p->kind != MESO_TILE_MAP_SPHERES)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "tile map: only Voronoi and sphere maps are generated");
    if (p->res < 1 || p->res > MESO_TILE_MAP_MAX_RES)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "tile map: resolution %u is not in 1..%u", p->res, MESO_TILE_MAP_MAX_RES);
    if (p->count < 1 || p->count > MESO_TILE_MAP_MAX_CELLS)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "tile map: %u %s is not in 1..%u", p->count,
                              p->kind == MESO_TILE_MAP_VORONOI ? "seeds" : "spheres", MESO_TILE_MAP_MAX_CELLS);
    if (p->kind == MESO_TILE_MAP_SPHERES && !(p->radius > 0.0 && p->radius <= 1.0))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "tile map: sphere radius %g is not in (0, 1] tile edges", p->radius);

    const uint32_t R = p->res, K = p->count;
    const uint64_t M = period(R);
    const size_t n = (size_t)R * R * R;
    const int nt = meso_bake_thread_count(threads);
    out->kind = p->kind;
    out->res = R;
    out->cell_count = K;
    out->cells = malloc(n * sizeof(uint16_t));
    out->seeds = malloc(3 * (size_t)K * sizeof(uint32_t));
    uint64_t* yz = malloc((size_t)nt * K * sizeof(uint64_t));
    if (!out->cells || !out->seeds || !yz) {
        free(yz);
        meso_tile_map_free(out);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "tile map: out of memory (R = %u)", R);
    }
    uint64_t state = p->rng_seed;
    for (size_t i = 0; i < 3 * (size_t)K; ++i)
        out->seeds[i] = (uint32_t)(((meso_splitmix64(&state) >> 32) * M) >> 32);
    if (p->kind == MESO_TILE_MAP_SPHERES) {
        const uint64_t r = (uint64_t)(p->radius * (double)M + 0.5);
        out->radius_sq = r * r;
    }

    const int64_t S = MESO_TILE_MAP_SUBSTEPS, Mi = (int64_t)M;
    const uint32_t* seeds = out->seeds;
    uint16_t* cells = out->cells;
    const int spheres = p->kind == MESO_TILE_MAP_SPHERES;
    const uint64_t rsq = out->radius_sq;
#ifdef _OPENMP
#pragma omp parallel for schedule(static) num_threads(nt)
#endif
    for (long line = 0; line < (long)R * R; ++line) {
#ifdef _OPENMP
        uint64_t* part = yz + (size_t)omp_get_thread_num() * K;
#else
        uint64_t* part = yz;
#endif
        const int64_t y = line % R, z = line / R;
        for (uint32_t k = 0; k < K; ++k)
            part[k] = axis_sq((2 * y + 1) * S, seeds[3 * (size_t)k + 1], Mi) +
                      axis_sq((2 * z + 1) * S, seeds[3 * (size_t)k + 2], Mi);
        uint16_t* row = cells + (size_t)line * R;
        for (uint32_t x = 0; x < R; ++x) {
            const int64_t px = (2 * (int64_t)x + 1) * S;
            uint64_t best = UINT64_MAX;
            uint16_t idx = 0;
            for (uint32_t k = 0; k < K; ++k) {
                if (part[k] >= best)
                    continue;
                const uint64_t d = axis_sq(px, seeds[3 * (size_t)k], Mi) + part[k];
                if (d < best) {
                    best = d;
                    idx = (uint16_t)(k + 1);
                }
            }
            row[x] = (spheres && best > rsq) ? 0 : idx;
        }
    }
    free(yz);
    return MESO_OK;
}

/* >>raw ---------------------------------------------------------------------- */

/* The R whose raw file has `size` bytes, or 0. */
static uint32_t res_of_size(uint64_t size)
{
    for (uint64_t r = 1; r <= MESO_TILE_MAP_MAX_RES; ++r)
        if (2 * r * r * r == size)
            return (uint32_t)r;
    return 0;
}

static meso_result wrong_size(meso_error* err, const char* what, uint64_t size, uint32_t res)
{
    const uint32_t fits = res_of_size(size);
    char hint[64] = "";
    if (fits)
        snprintf(hint, sizeof(hint), " (that is R = %u)", fits);
    return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_TILEMAP_ISSUE_CONTENT,
                          "tile map %s: %llu bytes, but R = %u needs 2 R^3 = %llu bytes of little-endian uint16%s",
                          what, (unsigned long long)size, res, 2ull * res * res * res, hint);
}

meso_result meso_tile_map_from_raw(const void* bytes, size_t size, uint32_t res, meso_tile_map* out,
                                   meso_error* err)
{
    if (!out || (!bytes && size))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "tile map: NULL argument");
    memset(out, 0, sizeof(*out));
    if (res < 1 || res > MESO_TILE_MAP_MAX_RES)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "tile map: resolution %u is not in 1..%u", res, MESO_TILE_MAP_MAX_RES);
    const size_t n = (size_t)res * res * res;
    if ((uint64_t)size != 2ull * n)
        return wrong_size(err, "bytes", size, res);
    out->cells = malloc(n * sizeof(uint16_t));
    if (!out->cells)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "tile map: out of memory (R = %u)", res);
    const uint8_t* b = bytes;
    uint16_t k = 0;
    for (size_t i = 0; i < n; ++i) {
        out->cells[i] = (uint16_t)(b[2 * i] | (uint16_t)b[2 * i + 1] << 8);
        if (out->cells[i] > k)
            k = out->cells[i];
    }
    out->kind = MESO_TILE_MAP_RAW;
    out->res = res;
    out->cell_count = k;
    return MESO_OK;
}

meso_result meso_tile_map_read_raw(const char* path, uint32_t res, meso_tile_map* out, meso_error* err)
{
    if (!path || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "tile map: NULL argument");
    memset(out, 0, sizeof(*out));
    if (res < 1 || res > MESO_TILE_MAP_MAX_RES)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TILEMAP_ISSUE_PARAMS,
                              "tile map %s: resolution %u is not in 1..%u", path, res, MESO_TILE_MAP_MAX_RES);
    FILE* fp = fopen(path, "rb");
    if (!fp)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_TILEMAP_ISSUE_FILE, "tile map %s: %s", path, strerror(errno));
    const size_t want = 2 * (size_t)res * res * res;
    /* A regular file of the wrong length is refused before the buffer is
     * allocated (R = 1024 asks for 2 GiB). Then read one byte more than
     * needed: a longer file (or a pipe) is refused without trusting its size
     * from the file system. */
    uint64_t file_size = 0;
    if (meso_regular_file_size(fp, &file_size) && file_size != want) {
        fclose(fp);
        return wrong_size(err, path, file_size, res);
    }
    uint8_t* buf = malloc(want + 1);
    if (!buf) {
        fclose(fp);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "tile map %s: out of memory", path);
    }
    const size_t got = fread(buf, 1, want + 1, fp);
    const int failed = ferror(fp);
    meso_result r;
    if (failed) {
        r = meso_bake_fail(err, MESO_ERR_IO, MESO_TILEMAP_ISSUE_FILE, "tile map %s: read error", path);
    } else if (got != want) {
        uint64_t size = got;
        if (got > want && fseek(fp, 0, SEEK_END) == 0) {
            const long end = ftell(fp);
            if (end > 0)
                size = (uint64_t)end;
        }
        char what[600];
        snprintf(what, sizeof(what), "%s", path);
        r = wrong_size(err, what, size, res);
    } else {
        r = meso_tile_map_from_raw(buf, want, res, out, err);
    }
    free(buf);
    fclose(fp);
    return r;
}
