/* png_io.c — see png_io.h. libpng's simplified API does the format work. */
#include "png_io.h"

#include <png.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int meso_png_write_rgba8(const char* path, const uint8_t* rgba, int width, int height, int flip_y, char* why,
                         int why_size)
{
    png_image img;
    memset(&img, 0, sizeof(img));
    img.version = PNG_IMAGE_VERSION;
    img.width = (png_uint_32)width;
    img.height = (png_uint_32)height;
    img.format = PNG_FORMAT_RGBA;
    const png_int_32 stride = flip_y ? -(png_int_32)(4 * width) : (png_int_32)(4 * width);
    if (!png_image_write_to_file(&img, path, 0, rgba, stride, NULL)) {
        snprintf(why, (size_t)why_size, "%s: %s", path, img.message);
        return -1;
    }
    return 0;
}

int meso_png_read_rgba8(const char* path, uint8_t** rgba, int* width, int* height, char* why, int why_size)
{
    *rgba = NULL;
    png_image img;
    memset(&img, 0, sizeof(img));
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_file(&img, path)) {
        snprintf(why, (size_t)why_size, "%s: %s", path, img.message);
        return -1;
    }
    img.format = PNG_FORMAT_RGBA;
    if (img.width == 0 || img.height == 0 || img.width > 65536 || img.height > 65536) {
        snprintf(why, (size_t)why_size, "%s: unsupported size %ux%u", path, img.width, img.height);
        png_image_free(&img);
        return -1;
    }
    uint8_t* buf = malloc(PNG_IMAGE_SIZE(img));
    if (!buf) {
        snprintf(why, (size_t)why_size, "%s: out of memory", path);
        png_image_free(&img);
        return -1;
    }
    if (!png_image_finish_read(&img, NULL, buf, 0, NULL)) {
        snprintf(why, (size_t)why_size, "%s: %s", path, img.message);
        free(buf);
        return -1;
    }
    *rgba = buf;
    *width = (int)img.width;
    *height = (int)img.height;
    return 0;
}
