/*
 * file_validate_cells.c — a cells object's chunks against its CELL record
 * (FORMAT.md §7.8, issues 4803..4806): meso_file_check_cells_level, which
 * the full tier runs for every CELL chunk (at its lod) and libmeso's and the
 * reference's cells loaders run before they trust sizes and ids. A level's
 * chunks are the ones meso_file_find_level resolves (FORMAT.md §7.10): a
 * native coarser level has its own CELL, TILE, ... at its lod. The CELL record alone is
 * file_validate.c's (check_cell, 4801..4802).
 */
#include "file_internal.h"

/* >>cells objects (FORMAT.md §7.8) ---------------------------------------- */

typedef struct cells_read {
    meso_file* f;
    uint32_t object;
    uint16_t lod;
    meso_error* err;
} cells_read;

/* Find `type` of the object at the level checked and check its element type and dims
 * against CELL (issue 4803); on success *index is the chunk. */
static meso_result cells_find(const cells_read* c, uint32_t type, unsigned dtypes, uint16_t comps, uint64_t d0,
                              uint64_t d1, uint64_t d2, int32_t* index)
{
    char cc[5];
    mesoi_fourcc_str(type, cc);
    int32_t i = meso_file_find_level(c->f, type, c->object, c->lod);
    if (i < 0)
        return mesoi_file_error(c->err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_CHUNKS, UINT64_MAX, -1,
                                "cells object %u: no %s chunk (level %u)", c->object, cc, c->lod);
    const meso_chunk_info* k = &c->f->chunks[i];
    if (!mesoi_is_dtype(k, dtypes) || k->components != comps || k->dims[0] != d0 || k->dims[1] != d1 || k->dims[2] != d2)
        return mesoi_file_error(c->err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_CHUNKS, UINT64_MAX, i,
                                "cells object %u: chunk %d (%s) is dtype %u x %u, %ux%ux%u; CELL implies %u "
                                "components, %llux%llux%llu",
                                c->object, (int)i, cc, k->dtype, k->components, k->dims[0], k->dims[1], k->dims[2],
                                comps, (unsigned long long)d0, (unsigned long long)d1, (unsigned long long)d2);
    *index = i;
    return MESO_OK;
}

/* Read a whole raw chunk into a fresh allocation. */
static meso_result cells_load(const cells_read* c, int32_t i, uint8_t** out)
{
    uint64_t n = c->f->chunks[i].decoded_size;
    *out = NULL;
    if (n > SIZE_MAX)
        return mesoi_file_error(c->err, MESO_ERR_UNSUPPORTED, MESO_ISSUE_API_TOO_LARGE, UINT64_MAX, i,
                                "chunk %d: %llu bytes do not fit in memory", (int)i, (unsigned long long)n);
    *out = (uint8_t*)mesoi_file_alloc(&c->f->alloc, (size_t)n);
    if (!*out)
        return mesoi_file_error(c->err, MESO_ERR_OUT_OF_MEMORY, MESO_ISSUE_API_MEMORY, UINT64_MAX, i,
                                "chunk %d: out of memory for %llu bytes", (int)i, (unsigned long long)n);
    return meso_file_read_chunk(c->f, (uint32_t)i, *out, (size_t)n, c->err);
}

static uint32_t popcount32(uint32_t v)
{
    uint32_t n = 0;
    for (; v; v &= v - 1)
        n++;
    return n;
}

/* MEMB: classes (no value 3, zero past T), rank, record count M, records
 * (no tag 3, zero past S). Returns a reason or NULL. */
static const char* check_memb(const uint8_t* d, uint64_t tiles, uint64_t mixed, uint32_t splits, uint32_t words,
                              uint64_t* where)
{
    const uint64_t cw = (tiles + 15) / 16;
    uint64_t seen = 0;
    for (uint64_t w = 0; w < cw; w++) {
        uint32_t v = mesoi_ld32(d + 4 * w), hi = v & 0xAAAAAAAAu, lo = v & 0x55555555u;
        *where = 4 * w;
        if (hi & (lo << 1))
            return "a tile class is 3";
        uint64_t used = tiles - 16 * w < 16 ? tiles - 16 * w : 16;
        if (used < 16 && (v >> (2 * used)) != 0)
            return "class bits past the last tile are not zero";
        *where = 4 * (cw + w);
        if (mesoi_ld32(d + 4 * (cw + w)) != seen)
            return "rank is not the number of MIXED tiles before the word";
        seen += popcount32(hi);
    }
    *where = 0;
    if (seen != mixed)
        return "the classes hold a different number of MIXED tiles than CELL";
    const uint64_t last = (uint64_t)splits - 16 * ((uint64_t)words - 1); /* split fields in the last word, 1..16 */
    for (uint64_t r = 0; r < mixed; r++)
        for (uint32_t w = 0; w < words; w++) {
            uint64_t off = 4 * (2 * cw + r * words + w);
            uint32_t v = mesoi_ld32(d + off);
            *where = off;
            if ((v & 0xAAAAAAAAu) & ((v & 0x55555555u) << 1))
                return "a record holds tag 3";
            if (w == words - 1 && last < 16 && (v >> (2 * last)) != 0)
                return "record bits past the last split cell are not zero";
        }
    return NULL;
}

meso_result meso_file_check_cells(meso_file* f, uint32_t object, meso_error* err)
{
    return mesoi_file_check_cells_keep(f, object, 0, NULL, NULL, err);
}

meso_result meso_file_check_cells_level(meso_file* f, uint32_t object, uint16_t lod, meso_error* err)
{
    return mesoi_file_check_cells_keep(f, object, lod, NULL, NULL, err);
}

meso_result mesoi_file_check_cells_keep(meso_file* f, uint32_t object, uint16_t lod, uint8_t** tile_out,
                                        uint8_t** memb_out, meso_error* err)
{
    if (f == NULL)
        return mesoi_file_error(err, MESO_ERR_INVALID_ARG, MESO_ISSUE_API_ARG, UINT64_MAX, -1,
                                "meso_file_check_cells: NULL file");
    cells_read c = {f, object, lod, err};
    uint8_t cell[MESO_CELL_RECORD_SIZE];
    uint8_t *tile = NULL, *splt = NULL, *memb = NULL;
    int32_t ci = meso_file_find_level(f, MESO_CHUNK_CELL, object, lod), ti, si, mi, ni, oi;
    if (ci < 0)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_CHUNKS, UINT64_MAX, -1,
                                "cells object %u: no CELL chunk (level %u)", object, lod);
    if (f->chunks[ci].decoded_size != MESO_CELL_RECORD_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_SIZE, UINT64_MAX, ci,
                                "chunk %d (CELL): size %llu, must be one 64-byte record", (int)ci,
                                (unsigned long long)f->chunks[ci].decoded_size);
    meso_result r = meso_file_read_chunk(f, (uint32_t)ci, cell, sizeof cell, err);
    if (r != MESO_OK)
        return r;
    uint64_t tiles = 1, R = mesoi_ld32(cell + MESO_CELL_OFF_TILE_RES);
    for (int a = 0; a < 3; a++)
        tiles *= mesoi_ld32(cell + MESO_CELL_OFF_TILES + 4 * a);
    const uint32_t S = mesoi_ld32(cell + MESO_CELL_OFF_SPLIT_COUNT), C = mesoi_ld32(cell + MESO_CELL_OFF_CELL_COUNT);
    const uint64_t M = mesoi_ld64(cell + MESO_CELL_OFF_MIXED_TILES);
    /* T <= 2^42 and M <= T (CELL's ranges), W < 2^28: M W may overflow, so
     * a MEMB longer than a u32 dims[0] can hold is a mismatch by itself. */
    const uint32_t W = (uint32_t)((2 * (uint64_t)S + 31) / 32);
    uint64_t memb_words = UINT64_MAX, mw;
    if (mesoi_mul_u64(M, W, &mw) && mw <= UINT32_MAX)
        memb_words = 2 * ((tiles + 15) / 16) + mw;
    const unsigned tile_types = S <= 65535 ? MESOI_DT(U16) : MESOI_DT(U32);
    if ((r = cells_find(&c, MESO_CHUNK_TILE, tile_types, 1, R, R, R, &ti)) != MESO_OK ||
        (r = cells_find(&c, MESO_CHUNK_SPLT, MESOI_DT(U32), MESO_SPLT_COMPONENTS, S, 1, 1, &si)) != MESO_OK ||
        (r = cells_find(&c, MESO_CHUNK_MEMB, MESOI_DT(U32), 1, memb_words, 1, 1, &mi)) != MESO_OK ||
        (r = cells_find(&c, MESO_CHUNK_NRMM, MESOI_DT(U16), 2, R, R, R, &ni)) != MESO_OK ||
        (r = cells_find(&c, MESO_CHUNK_COLR, MESOI_DT(U8), 4, R, R, R, &oi)) != MESO_OK)
        return r;
    (void)ni;
    (void)oi;
    if ((r = cells_load(&c, ti, &tile)) == MESO_OK) {
        const uint64_t n = R * R * R;
        for (uint64_t v = 0; v < n; v++) {
            uint32_t s = S <= 65535 ? mesoi_ld16(tile + 2 * v) : mesoi_ld32(tile + 4 * v);
            if (s > S) {
                r = mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_TILE, UINT64_MAX, ti,
                                     "chunk %d (TILE): voxel %llu holds split cell %u > split_count %u", (int)ti,
                                     (unsigned long long)v, s, S);
                break;
            }
        }
    }
    if (r == MESO_OK && (r = cells_load(&c, si, &splt)) == MESO_OK) {
        uint32_t prev = 0;
        for (uint32_t s = 0; s < S && r == MESO_OK; s++) {
            const uint8_t* q = splt + 4 * MESO_SPLT_COMPONENTS * (size_t)s;
            uint32_t cell_id = mesoi_ld32(q + 4 * MESO_SPLT_CELL), face = mesoi_ld32(q + 4 * MESO_SPLT_FACE_CODE);
            uint32_t index = mesoi_ld32(q + 4 * MESO_SPLT_TILE_INDEX);
            const char* why = cell_id != prev && cell_id != prev + 1 ? "cell ids do not run 1, 1.., 2.. without gaps"
                              : face > 63                             ? "face code above 63"
                              : index < 1 || index > 65535            ? "tile-map index outside 1..65535"
                              : s == S - 1 && cell_id != C            ? "the last split cell's cell is not cell_count"
                                                                      : NULL;
            if (why)
                r = mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_SPLT, UINT64_MAX, si,
                                     "chunk %d (SPLT): split cell %u: %s", (int)si, s + 1, why);
            prev = cell_id;
        }
    }
    if (r == MESO_OK && (r = cells_load(&c, mi, &memb)) == MESO_OK) {
        uint64_t where = 0;
        const char* why = check_memb(memb, tiles, M, S, W, &where);
        if (why)
            r = mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CELL_MEMB, UINT64_MAX, mi,
                                 "chunk %d (MEMB): %s (byte %llu)", (int)mi, why, (unsigned long long)where);
    }
    if (r == MESO_OK && tile_out) {
        *tile_out = tile;
        tile = NULL;
    }
    if (r == MESO_OK && memb_out) {
        *memb_out = memb;
        memb = NULL;
    }
    mesoi_file_free(&f->alloc, tile);
    mesoi_file_free(&f->alloc, splt);
    mesoi_file_free(&f->alloc, memb);
    return r;
}
