/* png_io.h — PNG read/write through libpng: RGBA8 images and grey data
 * images such as height maps (shared by the baker, the inspector's previews,
 * the viewer's screenshots and the tests). */
#ifndef MESO_PNG_IO_H
#define MESO_PNG_IO_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* Write RGBA8 rows top to bottom (or bottom to top with flip_y). Returns 0 on
 * success; on failure writes a reason to `why`. */
int meso_png_write_rgba8(const char* path, const uint8_t* rgba, int width, int height, int flip_y, char* why,
                         int why_size);
/* Read any 8/16-bit PNG as RGBA8 (malloc'd, free with free()). */
int meso_png_read_rgba8(const char* path, uint8_t** rgba, int* width, int* height, char* why, int why_size);
/* Read the first channel of any PNG (grey, or red of RGB(A)/palette images)
 * without gamma or colour conversion, for data images such as height maps:
 * *values (malloc'd, free with free()) gets width*height samples, rows top to
 * bottom, 0..255 when *bit_depth is 8 (files of 1..8 bits; 1, 2 and 4-bit grey
 * is scaled to 8 bits) and 0..65535 when it is 16. Returns 0 on success; on
 * failure writes a reason to `why`. */
int meso_png_read_channel0(const char* path, uint16_t** values, int* width, int* height, int* bit_depth, char* why,
                           int why_size);
/* The same from an open stream (not closed here; `name` is for messages),
 * with a byte budget checked against the header before the image is
 * decoded: what the reader allocates (the decoded rows, their pointers and
 * the samples) plus `extra_per_pixel` bytes a pixel for the caller's own
 * buffers. Over the budget: returns -2, nothing allocated, *need (may be
 * NULL) gets the bytes it would take and `why` says so. Other failures
 * (not a PNG, a bad header, truncated or corrupt image data): -1. */
int meso_png_read_channel0_fp(FILE* fp, const char* name, uint64_t max_bytes, unsigned extra_per_pixel,
                              uint16_t** values, int* width, int* height, int* bit_depth, uint64_t* need, char* why,
                              int why_size);
/* Colour images (a shell's --color): any PNG as 8-bit RGBA, rows top to
 * bottom, the stored (sRGB) values without gamma processing (palette and
 * grey expanded, 16-bit samples scaled to 8 bits, alpha 255 where the file
 * has none); *rgba is malloc'd (free with free()). Budget and return codes
 * as meso_png_read_channel0_fp (-2: over `max_bytes`, nothing allocated). */
int meso_png_read_rgba8_fp(FILE* fp, const char* name, uint64_t max_bytes, unsigned extra_per_pixel, uint8_t** rgba,
                           int* width, int* height, uint64_t* need, char* why, int why_size);
/* Write a grey PNG from width*height samples, rows top to bottom, with
 * bit_depth 8 (values 0..255) or 16. Returns 0 on success. */
int meso_png_write_gray(const char* path, const uint16_t* values, int width, int height, int bit_depth, char* why,
                        int why_size);

/* Encode 8-bit rows (channels 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA) top to
 * bottom (or bottom to top with flip_y) as a PNG in memory: *out (malloc'd,
 * free with free()) gets *size bytes. Returns 0 on success; on failure
 * writes a reason to `why`. */
int meso_png_encode_memory(const uint8_t* px, int width, int height, int channels, int flip_y, uint8_t** out,
                           size_t* size, char* why, int why_size);
/* Decode a PNG held in memory as RGBA8 rows top to bottom (malloc'd, free
 * with free()). Returns 0 on success. */
int meso_png_decode_memory_rgba8(const uint8_t* data, size_t size, uint8_t** rgba, int* width, int* height, char* why,
                                 int why_size);

#endif
