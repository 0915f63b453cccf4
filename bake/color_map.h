/* color_map.h — a 2D colour map from an 8-bit PNG, as the COLR chunk of a
 * frusta object stores it (FORMAT.md §7.2 kind 4): RGBA8, sRGB values as
 * the file holds them, W × H texels, row 0 the image's BOTTOM row (t = 0
 * at the bottom, as height:FILE.png relief maps: texture_function.h), so a
 * colour PNG and a height PNG of the same picture line up texel for texel.
 *
 * Decided here: only 8-bit PNGs are colour maps (grey, grey + alpha,
 * palette, RGB, RGBA; libpng's simplified API expands them to RGBA without
 * changing a value). 16-bit images are refused rather than converted: the
 * simplified API would treat their samples as linear and re-encode them,
 * and a colour map must hold the file's colours exactly (issue 16's goal:
 * mean error <= 2/255 against the source).
 */
#ifndef MESO_COLOR_MAP_H
#define MESO_COLOR_MAP_H

#include <stdint.h>

#include "meso_file.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Colour-map issue codes (meso_error.code):
 *   3560 the file cannot be opened or read (MESO_ERR_IO: missing, no permission)
 *   3561 the file is read but is no usable colour map (MESO_ERR_CORRUPT: not a
 *        PNG, corrupt or truncated, not 8 bits per sample, larger than 16384 a side) */
#define MESO_COLOR_ISSUE_FILE 3560u
#define MESO_COLOR_ISSUE_CONTENT 3561u

/* Largest side of a colour map (what GL implementations guarantee at least
 * since 4.x, and what libmeso uploads as one 2D texture). */
#define MESO_COLOR_MAP_MAX_SIDE 16384u

typedef struct meso_color_map {
    uint32_t width, height;
    uint8_t* rgba; /* width × height × 4, row 0 at the bottom; malloc'd */
} meso_color_map;

/* Loads `path`; `max_bytes` bounds what decoding takes (checked against the
 * PNG header before anything is decoded: MESO_LIMIT_ISSUE_PNG). */
meso_result meso_color_map_load_png(const char* path, uint64_t max_bytes, meso_color_map* out, meso_error* err);
void meso_color_map_free(meso_color_map* m);

#ifdef __cplusplus
}
#endif
#endif /* MESO_COLOR_MAP_H */
