/* png_io.h — 8-bit PNG read/write through libpng (shared by the baker, the
 * inspector's previews, the viewer's screenshots and the tests). */
#ifndef MESO_PNG_IO_H
#define MESO_PNG_IO_H

#include <stdint.h>

/* Write RGBA8 rows top to bottom (or bottom to top with flip_y). Returns 0 on
 * success; on failure writes a reason to `why`. */
int meso_png_write_rgba8(const char* path, const uint8_t* rgba, int width, int height, int flip_y, char* why,
                         int why_size);
/* Read any 8/16-bit PNG as RGBA8 (malloc'd, free with free()). */
int meso_png_read_rgba8(const char* path, uint8_t** rgba, int* width, int* height, char* why, int why_size);

#endif
