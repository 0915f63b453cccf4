/*
 * color_map.c — an 8-bit PNG as a frusta colour map (color_map.h states the
 * decisions): the header is checked first (signature, IHDR, bit depth, size
 * against the budget), then libpng decodes it to RGBA8 and the rows are
 * turned so row 0 is the bottom.
 */
#include "color_map.h"

#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "meso_bake.h"
#include "memory_budget.h"
#include "png_io.h"

static uint32_t be32(const uint8_t* p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | p[3];
}

void meso_color_map_free(meso_color_map* m)
{
    if (!m)
        return;
    free(m->rgba);
    memset(m, 0, sizeof(*m));
}

meso_result meso_color_map_load_png(const char* path, uint64_t max_bytes, meso_color_map* out, meso_error* err)
{
    memset(out, 0, sizeof(*out));
    FILE* fp = fopen(path, "rb");
    if (!fp)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_COLOR_ISSUE_FILE, "colour file %s: %s", path, strerror(errno));
    /* Signature (8), IHDR length and type (8), width, height, bit depth. */
    uint8_t head[25];
    const size_t got = fread(head, 1, sizeof(head), fp);
    const int read_error = ferror(fp);
    fclose(fp);
    if (read_error)
        return meso_bake_fail(err, MESO_ERR_IO, MESO_COLOR_ISSUE_FILE, "colour file %s: read error", path);
    static const uint8_t sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (got < sizeof(head) || memcmp(head, sig, 8) != 0 || memcmp(head + 12, "IHDR", 4) != 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_COLOR_ISSUE_CONTENT,
                              "colour file %s: not a PNG (the colour map must be an 8-bit PNG)", path);
    const uint32_t w = be32(head + 16), h = be32(head + 20);
    if (head[24] != 8)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_COLOR_ISSUE_CONTENT,
                              "colour file %s: %u bits per sample; colour maps are 8-bit PNGs", path, head[24]);
    if (w == 0 || h == 0 || w > MESO_COLOR_MAP_MAX_SIDE || h > MESO_COLOR_MAP_MAX_SIDE)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_COLOR_ISSUE_CONTENT,
                              "colour file %s: %u x %u pixels; each side must be 1..%u", path, w, h,
                              MESO_COLOR_MAP_MAX_SIDE);
    /* libpng's RGBA rows, the turned copy, and the file's rows being read. */
    const uint64_t need = 3 * 4 * (uint64_t)w * h;
    meso_result r = meso_budget_check(need, max_bytes, MESO_LIMIT_ISSUE_PNG, err, "colour file %s (%u x %u)", path, w, h);
    if (r != MESO_OK)
        return r;
    uint8_t* px = NULL;
    int pw = 0, ph = 0;
    char why[600];
    if (meso_png_read_rgba8(path, &px, &pw, &ph, why, (int)sizeof(why)) != 0)
        return meso_bake_fail(err, MESO_ERR_CORRUPT, MESO_COLOR_ISSUE_CONTENT, "colour file %s", why);
    const size_t row = 4 * (size_t)w;
    uint8_t* rgba = (uint32_t)pw == w && (uint32_t)ph == h ? malloc(row * h) : NULL;
    if (!rgba) {
        free(px);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "colour file %s: out of memory", path);
    }
    for (size_t y = 0; y < h; ++y) /* image rows run top to bottom; t = 0 is the bottom row */
        memcpy(rgba + y * row, px + ((size_t)h - 1 - y) * row, row);
    free(px);
    out->width = w;
    out->height = h;
    out->rgba = rgba;
    return MESO_OK;
}
