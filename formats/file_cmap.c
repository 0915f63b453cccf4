/*
 * file_cmap.c — the CMAP record of a shell's colour (FORMAT.md §7.2 "Shell
 * colour"): encoding, decoding and its content check (issues 4911, 4912).
 * The record is binary so that a runtime maps COLR to texture space without
 * reading META's JSON.
 */
#include "file_internal.h"

#include <math.h>

void meso_cmap_record_encode(const meso_cmap_record* rec, void* dst)
{
    uint8_t* p = (uint8_t*)dst;
    memset(p, 0, MESO_CMAP_RECORD_SIZE);
    mesoi_st32(p + MESO_CMAP_OFF_MAPPING, rec->mapping);
    mesoi_st32(p + MESO_CMAP_OFF_FLAGS, rec->flags);
    mesoi_stf32(p + MESO_CMAP_OFF_SCALE, rec->scale[0]);
    mesoi_stf32(p + MESO_CMAP_OFF_SCALE + 4, rec->scale[1]);
}

void meso_cmap_record_decode(const void* src, meso_cmap_record* rec)
{
    const uint8_t* p = (const uint8_t*)src;
    rec->mapping = mesoi_ld32(p + MESO_CMAP_OFF_MAPPING);
    rec->flags = mesoi_ld32(p + MESO_CMAP_OFF_FLAGS);
    rec->scale[0] = mesoi_ldf32(p + MESO_CMAP_OFF_SCALE);
    rec->scale[1] = mesoi_ldf32(p + MESO_CMAP_OFF_SCALE + 4);
}

meso_result mesoi_check_cmap(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n != MESO_CMAP_RECORD_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CMAP_SIZE, base, chunk,
                                "chunk %d (CMAP): size %zu, must be one 32-byte record", (int)chunk, n);
    meso_cmap_record r;
    meso_cmap_record_decode(d, &r);
    int reserved_zero = 1;
    for (int k = 0; k < MESO_CMAP_SIZE_RESERVED; k++)
        reserved_zero = reserved_zero && d[MESO_CMAP_OFF_RESERVED + k] == 0;
    const int scale_ok = isfinite(r.scale[0]) && r.scale[0] > 0.0f && isfinite(r.scale[1]) && r.scale[1] > 0.0f;
    const char* why = r.mapping > MESO_CMAP_BASE                                   ? "mapping is neither 0 nor 1"
                      : r.flags                                                    ? "unknown flag bits"
                      : !scale_ok                                                  ? "scale not finite and > 0"
                      : r.mapping == MESO_CMAP_TILED && (r.scale[0] != 1.0f || r.scale[1] != 1.0f)
                          ? "a TILED mapping has scale 1, 1"
                      : !reserved_zero ? "reserved bytes not zero"
                                       : NULL;
    if (why)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_CMAP_VALUE, base, chunk, "chunk %d (CMAP): %s",
                                (int)chunk, why);
    return MESO_OK;
}
