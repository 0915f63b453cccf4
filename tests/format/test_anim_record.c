/*
 * test_anim_record.c — the ANIM record of an animated texture function
 * (FORMAT.md §7.2 "Animated texture functions"; the boiling textures of
 * papers/volume-textures-lp-averaged-shells.md §6): encode/decode round
 * trip, the frame a time selects (looped, held, before time0, rounding at
 * t_k = time0 + k / fps), and the writer refusing records the reader
 * refuses (4901 size, 4902 values) while accepting a good one.
 */
#undef NDEBUG
#include "meso_file.h"
#include "meso_layout.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

static meso_result add(const void* rec, size_t size, uint32_t* code)
{
    meso_writer* w = NULL;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    const meso_chunk_desc d = {.type = MESO_CHUNK_ANIM, .object = 1, .dtype = MESO_DTYPE_BYTES};
    meso_error e;
    memset(&e, 0, sizeof(e));
    const meso_result r = meso_writer_add(w, &d, rec, size, &e);
    *code = e.code;
    meso_writer_destroy(w);
    return r;
}

int main(void)
{
    const meso_anim_record a = {.frame_count = 8, .flags = MESO_ANIM_FLAG_LOOP, .fps = 4.0f, .time0 = 0.25f};
    uint8_t buf[MESO_ANIM_RECORD_SIZE + 8];
    memset(buf, 0xAB, sizeof(buf));
    meso_anim_record_encode(&a, buf);
    for (int k = MESO_ANIM_OFF_RESERVED; k < MESO_ANIM_RECORD_SIZE; ++k)
        assert(buf[k] == 0);
    assert(buf[MESO_ANIM_RECORD_SIZE] == 0xAB); /* writes exactly 32 bytes */
    meso_anim_record b;
    meso_anim_record_decode(buf, &b);
    assert(b.frame_count == 8 && b.flags == MESO_ANIM_FLAG_LOOP && b.fps == 4.0f && b.time0 == 0.25f);

    /* t_k = time0 + k / fps is frame k, for every k, also many loops on */
    for (uint32_t k = 0; k < 64; ++k)
        assert(meso_anim_frame_at(&a, 0.25 + k / 4.0) == k % 8);
    assert(meso_anim_frame_at(&a, 0.25 + 0.1249) == 0);
    assert(meso_anim_frame_at(&a, 0.25 - 0.01) == 7); /* before time0: the loop runs backwards */
    assert(meso_anim_frame_at(&a, 0.25 - 2.0) == 0);
    meso_anim_record held = a;
    held.flags = 0;
    assert(meso_anim_frame_at(&held, -5.0) == 0 && meso_anim_frame_at(&held, 100.0) == 7);
    assert(meso_anim_frame_at(&held, 0.25 + 3 / 4.0) == 3);
    meso_anim_record one = a;
    one.frame_count = 1;
    assert(meso_anim_frame_at(&one, 12.3) == 0);
    assert(meso_anim_frame_at(&a, NAN) == 0);

    /* the writer checks contents as the reader does */
    uint32_t code = 0;
    assert(add(buf, MESO_ANIM_RECORD_SIZE, &code) == MESO_OK);
    assert(add(buf, 16, &code) == MESO_ERR_INVALID_ARG && code == MESO_ISSUE_ANIM_SIZE);
    const struct {
        meso_anim_record r;
        int reserved;
    } bad[] = {{{0, 1, 4.0f, 0.0f}, 0},        {{MESO_ANIM_MAX_FRAMES + 1, 1, 4.0f, 0.0f}, 0},
               {{8, 2, 4.0f, 0.0f}, 0},        {{8, 1, 0.0f, 0.0f}, 0},
               {{8, 1, -1.0f, 0.0f}, 0},       {{8, 1, INFINITY, 0.0f}, 0},
               {{8, 1, 4.0f, NAN}, 0},         {{8, 1, 4.0f, 0.0f}, 1}};
    for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i) {
        uint8_t r[MESO_ANIM_RECORD_SIZE];
        meso_anim_record_encode(&bad[i].r, r);
        if (bad[i].reserved)
            r[MESO_ANIM_OFF_RESERVED + 15] = 1;
        assert(add(r, sizeof(r), &code) == MESO_ERR_INVALID_ARG && code == MESO_ISSUE_ANIM_VALUE);
    }
    printf("test_anim_record: ok\n");
    return 0;
}
