/*
 * file_anim.c — the ANIM record of an animated texture function (FORMAT.md
 * §7.2 "Animated texture functions"; the boiling and growing textures of
 * papers/volume-textures-lp-averaged-shells.md §6): encoding, decoding, its
 * content check (issues 4901, 4902) and the frame a time selects.
 */
#include "file_internal.h"

#include <math.h>

void meso_anim_record_encode(const meso_anim_record* rec, void* dst)
{
    uint8_t* p = (uint8_t*)dst;
    memset(p, 0, MESO_ANIM_RECORD_SIZE);
    mesoi_st32(p + MESO_ANIM_OFF_FRAME_COUNT, rec->frame_count);
    mesoi_st32(p + MESO_ANIM_OFF_FLAGS, rec->flags);
    mesoi_stf32(p + MESO_ANIM_OFF_FPS, rec->fps);
    mesoi_stf32(p + MESO_ANIM_OFF_TIME0, rec->time0);
}

void meso_anim_record_decode(const void* src, meso_anim_record* rec)
{
    const uint8_t* p = (const uint8_t*)src;
    rec->frame_count = mesoi_ld32(p + MESO_ANIM_OFF_FRAME_COUNT);
    rec->flags = mesoi_ld32(p + MESO_ANIM_OFF_FLAGS);
    rec->fps = mesoi_ldf32(p + MESO_ANIM_OFF_FPS);
    rec->time0 = mesoi_ldf32(p + MESO_ANIM_OFF_TIME0);
}

uint32_t meso_anim_frame_at(const meso_anim_record* rec, double t)
{
    const uint32_t n = rec->frame_count;
    const double x = floor((t - (double)rec->time0) * (double)rec->fps + 1e-4);
    if (n <= 1 || !(x == x))
        return 0;
    if (rec->flags & MESO_ANIM_FLAG_LOOP) {
        const double m = fmod(x, (double)n);
        return (uint32_t)(m < 0 ? m + n : m);
    }
    return x <= 0 ? 0 : x >= n - 1 ? n - 1 : (uint32_t)x;
}

meso_result mesoi_check_anim(const uint8_t* d, size_t n, int32_t chunk, uint64_t base, meso_error* err)
{
    if (n != MESO_ANIM_RECORD_SIZE)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_ANIM_SIZE, base, chunk,
                                "chunk %d (ANIM): size %zu, must be one 32-byte record", (int)chunk, n);
    meso_anim_record r;
    meso_anim_record_decode(d, &r);
    int reserved_zero = 1;
    for (int k = 0; k < MESO_ANIM_SIZE_RESERVED; k++)
        reserved_zero = reserved_zero && d[MESO_ANIM_OFF_RESERVED + k] == 0;
    const char* why = r.frame_count < 1 || r.frame_count > MESO_ANIM_MAX_FRAMES ? "frame_count outside 1..4096"
                      : r.flags & ~MESO_ANIM_FLAG_LOOP                        ? "unknown flag bits"
                      : !(isfinite(r.fps) && r.fps > 0.0f)                    ? "fps not finite and > 0"
                      : !isfinite(r.time0)                                    ? "time0 not finite"
                      : !reserved_zero                                        ? "reserved bytes not zero"
                                                                              : NULL;
    if (why)
        return mesoi_file_error(err, MESO_ERR_CORRUPT, MESO_ISSUE_ANIM_VALUE, base, chunk, "chunk %d (ANIM): %s",
                                (int)chunk, why);
    return MESO_OK;
}
