/*
 * fuzz_png.c — libFuzzer target for the PNG reader as height maps use it
 * (bake/image/png_io.c, meso_png_read_channel0_fp; texture_function.c's
 * height:FILE.png). The input is the file; it is read through fmemopen with
 * a 16 MiB budget, so a header claiming more pixels must be refused (-2)
 * before anything is allocated instead of being decoded.
 *
 *   # replay (any compiler, meson test --suite fuzz):
 *   ./build/tests/fuzz/fuzz_png tests/fuzz/corpus/png
 *   # fuzz (clang, -Dfuzzing_engine=libfuzzer; meson test --suite fuzz-session):
 *   cp -r tests/fuzz/corpus/png /tmp/c && ./build-fuzz/tests/fuzz/fuzz_png /tmp/c -max_len=4096
 *
 * What it asserts beyond "no crash, no leak": success gives 1..65535 pixels
 * a side within the budget, samples within the bit depth (8-bit: <= 255),
 * and a refusal over the budget names a need above it; failures hand back
 * no buffer.
 */
#undef NDEBUG /* this file uses assert() to check the reader's contract */
#include <assert.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

#include "png_io.h"

#define BUDGET ((uint64_t)16 << 20) /* small: each input decodes fast, a header over it is refused */
#define EXTRA 10u /* the height-map loader's bytes per pixel (texture_function.c) */

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    if (size == 0)
        return 0;
    FILE* fp = fmemopen((void*)data, size, "rb");
    if (!fp)
        return 0;
    uint16_t* px = NULL;
    int w = 0, h = 0, depth = 0;
    uint64_t need = 0;
    char why[256];
    const int rc = meso_png_read_channel0_fp(fp, "fuzz.png", BUDGET, EXTRA, &px, &w, &h, &depth, &need, why,
                                             (int)sizeof why);
    fclose(fp);
    if (rc == 0) {
        assert(px && w >= 1 && h >= 1 && w <= 65535 && h <= 65535);
        assert(depth == 8 || depth == 16);
        assert((uint64_t)w * (uint64_t)h * (2 + EXTRA) <= BUDGET);
        if (depth == 8)
            for (size_t i = 0; i < (size_t)w * (size_t)h; ++i)
                assert(px[i] <= 255);
        free(px);
    } else {
        assert(px == NULL && (rc == -1 || rc == -2) && why[0]);
        assert(rc != -2 || need > BUDGET);
    }
    return 0;
}
