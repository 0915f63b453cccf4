/* A cells object's chunks (bake/cells_chunks.c, FORMAT.md §7.8) written,
 * read back through the format library and checked against recomputation:
 *  - MEMB decoded here from FORMAT.md's words alone (class, rank, popcount)
 *    equals meso_membership_get / meso_membership_tile for every split cell
 *    of every tile; TILE and SPLT equal the split cells;
 *  - meso_file_check_cells and the full tier accept the file;
 *  - NRMM: octahedral round trip under 0.01 degrees; every stored normal
 *    equals the recomputed one; on border voxels it points out of the cell
 *    (a 2-voxel step along it leaves the cell, against it stays, on at least 90 %);
 *  - COLR: alpha marks cells, one colour per tile-map index up to the grain;
 *  - the same bytes for 1 and 2 threads. */
#include "test_util.h"

#include <math.h>
#include <string.h>

#include "adapters.h"
#include "cells_chunks.h"
#include "meso_layout.h"

typedef struct baked {
    meso_tile_map tm;
    meso_split_cells sc;
    meso_membership mb;
    meso_cells_chunks cc;
    meso_voxel_grid g;
} baked;

static void bake(const meso_mesh* m, int threads, baked* b)
{
    meso_error err = {0};
    memset(b, 0, sizeof *b);
    meso_tile_map_params p = {.kind = MESO_TILE_MAP_VORONOI, .res = 16, .count = 12, .rng_seed = 7};
    assert(meso_tile_map_generate(&p, threads, &b->tm, &err) == MESO_OK);
    assert(meso_split_cells_compute(&b->tm, threads, &b->sc, &err) == MESO_OK);
    assert(meso_voxel_grid_fit(m, 6, 16, 1.0, &b->g, &err) == MESO_OK);
    for (int k = 0; k < 3; ++k)
        b->g.origin[k] = (double)(float)b->g.origin[k];
    b->g.voxel_size = (double)(float)b->g.voxel_size;
    assert(meso_membership_compute(m, &b->g, &b->sc, MESO_VOXELIZE_AUTO, threads, &b->mb, &err) == MESO_OK);
    assert(meso_cells_chunks_build(&b->tm, &b->sc, &b->mb, b->g.origin, b->g.voxel_size, "hash:3", threads, &b->cc,
                                   &err) == MESO_OK);
}

static void baked_free(baked* b)
{
    meso_cells_chunks_free(&b->cc);
    meso_membership_free(&b->mb);
    meso_split_cells_free(&b->sc);
    meso_tile_map_free(&b->tm);
}

static uint8_t* write_object(const baked* b, size_t* size)
{
    const meso_cells_chunks* c = &b->cc;
    const uint32_t R = b->tm.res, S = b->sc.split_count;
    meso_writer* w = NULL;
    meso_error err = {0};
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    meso_chunk_desc d[6] = {
        {.type = MESO_CHUNK_CELL, .object = 1},
        {.type = MESO_CHUNK_TILE, .object = 1, .dtype = c->tile_dtype, .dims = {R, R, R}},
        {.type = MESO_CHUNK_SPLT, .object = 1, .dtype = MESO_DTYPE_U32, .components = 6, .dims = {S, 1, 1}},
        {.type = MESO_CHUNK_MEMB, .object = 1, .dtype = MESO_DTYPE_U32, .dims = {(uint32_t)(c->memb_size / 4), 1, 1}},
        {.type = MESO_CHUNK_NRMM, .object = 1, .dtype = MESO_DTYPE_U16, .components = 2, .dims = {R, R, R}},
        {.type = MESO_CHUNK_COLR, .object = 1, .dtype = MESO_DTYPE_U8, .components = 4, .dims = {R, R, R}},
    };
    const void* data[6] = {c->cell, c->tile, c->splt, c->memb, c->nrmm, c->colr};
    const size_t sizes[6] = {sizeof c->cell, c->tile_size, c->splt_size, c->memb_size, c->nrmm_size, c->colr_size};
    for (int i = 0; i < 6; ++i)
        assert(meso_writer_add(w, &d[i], data[i], sizes[i], &err) == MESO_OK);
    assert(meso_writer_finish(w, NULL, 0, size) == MESO_OK);
    uint8_t* mem = (uint8_t*)malloc(*size);
    assert(mem && meso_writer_finish(w, mem, *size, size) == MESO_OK);
    meso_writer_destroy(w);
    return mem;
}

static void* read_back(meso_file* f, uint32_t type, size_t* size)
{
    int32_t i = meso_file_find(f, type, 1, 0);
    assert(i >= 0);
    *size = (size_t)meso_file_chunk(f, (uint32_t)i)->decoded_size;
    void* p = malloc(*size);
    meso_error err = {0};
    assert(p && meso_file_read_chunk(f, (uint32_t)i, p, *size, &err) == MESO_OK);
    return p;
}

static uint32_t ld32(const uint8_t* p) { return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24; }

/* Tag of split s (1..S) in tile t from the MEMB words, FORMAT.md §7.2 kind 3. */
static unsigned memb_tag(const uint32_t* w, uint64_t T, uint32_t S, uint64_t t, uint32_t s, unsigned* cls)
{
    const uint64_t cw = (T + 15) / 16;
    const uint32_t W = (2 * S + 31) / 32, word = w[t / 16];
    *cls = (word >> (2 * (t % 16))) & 3u;
    if (*cls != 2)
        return *cls;
    uint64_t rec = w[cw + t / 16];
    for (uint64_t k = 0; k < t % 16; ++k)
        rec += ((word >> (2 * k)) & 3u) == 2;
    return (w[2 * cw + rec * W + (s - 1) / 16] >> (2 * ((s - 1) % 16))) & 3u;
}

static void octahedral_round_trip_is_accurate(void)
{
    uint64_t st = 11;
    double worst = 0;
    for (int i = 0; i < 200000; ++i) {
        double v[3], l = 0;
        for (int k = 0; k < 3; ++k) {
            v[k] = (double)(meso_splitmix64(&st) >> 11) / 9007199254740992.0 * 2 - 1;
            l += v[k] * v[k];
        }
        if (l < 1e-6 || l > 1)
            continue;
        for (int k = 0; k < 3; ++k)
            v[k] /= sqrt(l);
        uint16_t e[2];
        double n[3];
        meso_octa_encode(v, e);
        meso_octa_decode(e, n);
        double dot = v[0] * n[0] + v[1] * n[1] + v[2] * n[2];
        worst = fmax(worst, acos(fmin(1.0, dot)) * 180 / M_PI);
    }
    printf("octahedral U16x2: worst angle error %.5f degrees\n", worst);
    assert(worst < 0.01);
}

static void chunks_read_back_equal_recomputation(void)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data("sphere.obj"), &m, NULL, &err) == MESO_OK);
    baked b, b1;
    bake(&m, 2, &b);
    bake(&m, 1, &b1);
    /* 1 = 2 threads, byte for byte */
    assert(!memcmp(b.cc.cell, b1.cc.cell, sizeof b.cc.cell));
    assert(b.cc.memb_size == b1.cc.memb_size && !memcmp(b.cc.memb, b1.cc.memb, b.cc.memb_size));
    assert(!memcmp(b.cc.nrmm, b1.cc.nrmm, b.cc.nrmm_size) && !memcmp(b.cc.colr, b1.cc.colr, b.cc.colr_size));
    assert(!memcmp(b.cc.tile, b1.cc.tile, b.cc.tile_size) && !memcmp(b.cc.splt, b1.cc.splt, b.cc.splt_size));
    baked_free(&b1);

    size_t fsize = 0;
    uint8_t* mem = write_object(&b, &fsize);
    meso_file* f = NULL;
    assert(meso_file_open_memory(mem, fsize, NULL, &f, &err) == MESO_OK);
    assert(meso_file_check_cells(f, 1, &err) == MESO_OK);
    assert(meso_file_validate(f, MESO_CHECK_FULL, NULL, NULL) == MESO_OK);

    const uint32_t R = b.tm.res, S = b.sc.split_count;
    const size_t n = (size_t)R * R * R;
    size_t sz;
    /* CELL */
    uint8_t* cell = (uint8_t*)read_back(f, MESO_CHUNK_CELL, &sz);
    assert(ld32(cell + MESO_CELL_OFF_TILE_RES) == R && ld32(cell + MESO_CELL_OFF_SPLIT_COUNT) == S);
    float h;
    memcpy(&h, cell + MESO_CELL_OFF_VOXEL_SIZE, 4);
    assert((double)h == b.g.voxel_size);
    for (int k = 0; k < 3; ++k) {
        float o;
        memcpy(&o, cell + MESO_CELL_OFF_ORIGIN + 4 * k, 4);
        assert((double)o == b.g.origin[k] && ld32(cell + MESO_CELL_OFF_TILES + 4 * k) == b.g.tiles[k]);
    }
    free(cell);
    /* TILE, SPLT */
    uint16_t* tile = (uint16_t*)read_back(f, MESO_CHUNK_TILE, &sz);
    assert(sz == 2 * n);
    for (size_t v = 0; v < n; ++v)
        assert(tile[v] == b.sc.voxel_split[v]);
    uint32_t* splt = (uint32_t*)read_back(f, MESO_CHUNK_SPLT, &sz);
    for (uint32_t s = 0; s < S; ++s) {
        const uint32_t* q = splt + 6 * s;
        assert(q[0] == b.sc.splits[s].cell && q[1] == b.sc.splits[s].face_code && q[2] == b.sc.splits[s].tile_index);
        for (int k = 0; k < 3; ++k)
            assert((int32_t)q[3 + k] == b.sc.splits[s].offset[k]);
    }
    free(splt);
    /* MEMB against the library's accessors */
    uint32_t* memb = (uint32_t*)read_back(f, MESO_CHUNK_MEMB, &sz);
    uint64_t tags[3] = {0, 0, 0}, tiles_checked = 0;
    for (uint32_t tz = 0; tz < b.g.tiles[2]; ++tz)
        for (uint32_t ty = 0; ty < b.g.tiles[1]; ++ty)
            for (uint32_t tx = 0; tx < b.g.tiles[0]; ++tx) {
                uint64_t t = tx + (uint64_t)b.g.tiles[0] * (ty + (uint64_t)b.g.tiles[1] * tz);
                unsigned cls = 0;
                for (uint32_t s = 1; s <= S; ++s) {
                    unsigned tag = memb_tag(memb, b.mb.tile_count, S, t, s, &cls);
                    assert(tag == (unsigned)meso_membership_get(&b.mb, tx, ty, tz, s));
                    tags[tag]++;
                }
                assert(cls == (unsigned)meso_membership_tile(&b.mb, tx, ty, tz));
                tiles_checked++;
            }
    printf("MEMB from the file = meso_membership_get: %llu tiles x %u split cells (%llu outside, %llu inside, %llu "
           "intersected)\n",
           (unsigned long long)tiles_checked, S, (unsigned long long)tags[0], (unsigned long long)tags[1],
           (unsigned long long)tags[2]);
    assert(tags[1] > 0 && tags[0] > 0 && tags[2] > 0);
    free(memb);
    /* NRMM */
    uint16_t* nrmm = (uint16_t*)read_back(f, MESO_CHUNK_NRMM, &sz);
    uint64_t border = 0, out_ok = 0, in_ok = 0;
    double worst = 0;
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                size_t v = x + (size_t)R * (y + (size_t)R * z);
                double nrm[3], ref[3];
                meso_octa_decode(nrmm + 2 * v, nrm);
                assert(fabs(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2] - 1) < 1e-9);
                meso_cells_normal_sum(&b.tm, x, y, z, ref);
                double l = sqrt(ref[0] * ref[0] + ref[1] * ref[1] + ref[2] * ref[2]);
                if (l == 0) {
                    assert(nrm[2] > 0.999999);
                    continue;
                }
                double dot = (ref[0] * nrm[0] + ref[1] * nrm[1] + ref[2] * nrm[2]) / l;
                worst = fmax(worst, acos(fmin(1.0, dot)) * 180 / M_PI);
                /* border voxel: a 26-neighbour of another index */
                const uint16_t me = meso_tile_map_eval(&b.tm, x, y, z);
                int is_border = 0;
                for (int d = 0; d < 27 && !is_border; ++d)
                    is_border = meso_tile_map_eval(&b.tm, (int64_t)x + d % 3 - 1, (int64_t)y + d / 3 % 3 - 1,
                                                   (int64_t)z + d / 9 - 1) != me;
                if (!is_border)
                    continue;
                border++;
                int64_t o[3], i[3];
                for (int k = 0; k < 3; ++k) {
                    const int64_t c = k == 0 ? x : k == 1 ? y : z;
                    o[k] = c + (int64_t)floor(0.5 + 2.0 * nrm[k]);
                    i[k] = c + (int64_t)floor(0.5 - 2.0 * nrm[k]);
                }
                out_ok += meso_tile_map_eval(&b.tm, o[0], o[1], o[2]) != me;
                in_ok += meso_tile_map_eval(&b.tm, i[0], i[1], i[2]) == me;
            }
    printf("NRMM: stored = recomputed within %.4f degrees; %llu border voxels: a 2-voxel step along the normal "
           "leaves the cell at %.1f %%, against it stays at %.1f %%\n",
           worst, (unsigned long long)border, 100.0 * out_ok / border, 100.0 * in_ok / border);
    assert(worst < 0.01 && border > 0);
    assert(out_ok >= 0.9 * border && in_ok >= 0.9 * border);
    free(nrmm);
    /* COLR */
    uint8_t* colr = (uint8_t*)read_back(f, MESO_CHUNK_COLR, &sz);
    uint8_t lo[65536][3], hi[65536][3];
    memset(lo, 255, sizeof lo);
    memset(hi, 0, sizeof hi);
    for (size_t v = 0; v < n; ++v) {
        const uint16_t idx = b.tm.cells[v];
        assert(colr[4 * v + 3] == (idx ? 255 : 0));
        for (int k = 0; k < 3 && idx; ++k) {
            lo[idx][k] = colr[4 * v + k] < lo[idx][k] ? colr[4 * v + k] : lo[idx][k];
            hi[idx][k] = colr[4 * v + k] > hi[idx][k] ? colr[4 * v + k] : hi[idx][k];
        }
    }
    for (uint32_t idx = 1; idx <= b.tm.cell_count; ++idx)
        for (int k = 0; k < 3; ++k)
            assert(hi[idx][k] < lo[idx][k] || hi[idx][k] - lo[idx][k] <= 20); /* one colour +- the grain */
    free(colr);
    free(tile);
    meso_file_close(f);
    free(mem);
    baked_free(&b);
    meso_mesh_free(&m);
}

int main(void)
{
    octahedral_round_trip_is_accurate();
    chunks_read_back_equal_recomputation();
    printf("test_cells_chunks: ok\n");
    return 0;
}
