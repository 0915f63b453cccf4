/* png_io.c — see png_io.h. libpng's simplified API does the format work. */
#include "png_io.h"

#include <png.h>
#include <setjmp.h>
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

/* >>data images ----------------------------------------------------------
 * The simplified API converts between sRGB and linear when bit depths differ,
 * which would bend a height map; these two use the low-level API, where no
 * gamma processing happens unless asked for. libpng reports errors by
 * longjmp from the error callback; everything that must survive it lives in
 * a context struct reached through a pointer, never in locals modified
 * after setjmp. */

typedef struct png_ctx {
    char* why;
    int why_size;
    const char* path;
    FILE* fp;
    int own_fp;          /* fp is closed by ctx_free */
    uint64_t max_bytes;  /* read: budget for what the image needs */
    unsigned extra;      /* read: the caller's bytes per pixel, counted in it */
    uint64_t need;       /* read: what it needs (set when over the budget) */
    int rgba8;           /* read: expand to 8-bit RGBA (meso_png_read_rgba8_fp) */
    uint8_t* pixels;    /* decoded image (read) */
    png_bytep* rows;    /* row pointers */
} png_ctx;

static void ctx_error(png_structp png, png_const_charp msg)
{
    png_ctx* c = png_get_error_ptr(png);
    snprintf(c->why, (size_t)c->why_size, "%s: %s", c->path, msg);
    png_longjmp(png, 1);
}

static void ctx_warning(png_structp png, png_const_charp msg)
{
    (void)png;
    (void)msg;
}

static void ctx_free(png_ctx* c)
{
    free(c->pixels);
    free(c->rows);
    if (c->fp && c->own_fp)
        fclose(c->fp);
    c->pixels = NULL;
    c->rows = NULL;
    c->fp = NULL;
}

/* Decode after setjmp; fills c->pixels. */
static int read_body(png_structp png, png_infop info, png_ctx* c, int* width, int* height, int* depth, int* channels)
{
    png_init_io(png, c->fp);
    png_set_sig_bytes(png, 8);
    png_set_user_limits(png, 65536, 65536);
    png_set_chunk_malloc_max(png, (png_alloc_size_t)8 << 20);
    /* Ancillary chunks are skipped unread: libpng 1.6.39 allocates a zTXt
     * chunk's declared length (2 GB in a 205-byte file, found by
     * tests/fuzz/fuzz_png.c) before it finds the stream too short, and none
     * of them changes channel 0 (no gamma or colour conversion is done). */
    static const png_byte ignored[] = "bKGD\0cHRM\0eXIf\0gAMA\0hIST\0iCCP\0iTXt\0oFFs\0pCAL\0pHYs\0sBIT\0"
                                      "sCAL\0sPLT\0sRGB\0tEXt\0tIME\0zTXt";
    png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, ignored, (int)(sizeof ignored / 5));
    png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, NULL, 0); /* and chunks libpng does not know */
    png_read_info(png, info);
    png_set_expand(png); /* palette -> RGB, grey < 8 bits -> 8 bits, tRNS -> alpha */
    if (c->rgba8) {
        /* Colour images: the stored sRGB values as they are (no gamma
         * processing), 16-bit samples scaled to 8 bits, grey to RGB, opaque
         * alpha added where there is none. */
        png_set_scale_16(png);
        png_set_gray_to_rgb(png);
        png_set_add_alpha(png, 0xFF, PNG_FILLER_AFTER);
    }
    (void)png_set_interlace_handling(png);
    png_read_update_info(png, info);
    const png_uint_32 w = png_get_image_width(png, info), h = png_get_image_height(png, info);
    const size_t rowbytes = png_get_rowbytes(png, info);
    *depth = png_get_bit_depth(png, info);
    *channels = png_get_channels(png, info);
    if (w == 0 || h == 0 || (*depth != 8 && *depth != 16)) {
        snprintf(c->why, (size_t)c->why_size, "%s: unsupported PNG layout", c->path);
        return -1;
    }
    /* The header's size against the budget, before the rows are allocated:
     * decoded rows, row pointers, 2-byte samples, the caller's buffers.
     * (w, h < 2^16 and rowbytes <= 8 w, so nothing here overflows.) */
    const uint64_t px = (uint64_t)w * h;
    c->need = (uint64_t)rowbytes * h + sizeof(png_bytep) * (uint64_t)h + (2 + (uint64_t)c->extra) * px;
    if (c->need > c->max_bytes) {
        snprintf(c->why, (size_t)c->why_size, "%s: %ux%u pixels (as its header says; %d-bit, %d channel%s)", c->path,
                 (unsigned)w, (unsigned)h, *depth, *channels, *channels > 1 ? "s" : "");
        return -2;
    }
    c->pixels = malloc(rowbytes * h);
    c->rows = malloc(sizeof(png_bytep) * h);
    if (!c->pixels || !c->rows) {
        snprintf(c->why, (size_t)c->why_size, "%s: out of memory", c->path);
        return -1;
    }
    for (png_uint_32 y = 0; y < h; ++y)
        c->rows[y] = c->pixels + rowbytes * y;
    png_read_image(png, c->rows);
    png_read_end(png, NULL);
    *width = (int)w;
    *height = (int)h;
    return 0;
}

int meso_png_read_channel0(const char* path, uint16_t** values, int* width, int* height, int* bit_depth, char* why,
                           int why_size)
{
    *values = NULL;
    FILE* fp = fopen(path, "rb");
    if (!fp) {
        snprintf(why, (size_t)why_size, "%s: can not open", path);
        return -1;
    }
    const int rc = meso_png_read_channel0_fp(fp, path, UINT64_MAX, 0, values, width, height, bit_depth, NULL, why,
                                             why_size);
    fclose(fp);
    return rc;
}

/* Signature, then read_body under setjmp: c->rows hold the decoded image
 * on 0; -1 or -2 (over the budget, c->need set) with `why` filled. */
static int read_rows(png_ctx* c, int* w, int* h, int* depth, int* channels)
{
    uint8_t sig[8];
    if (fread(sig, 1, 8, c->fp) != 8 || png_sig_cmp(sig, 0, 8)) {
        snprintf(c->why, (size_t)c->why_size, "%s: not a PNG file", c->path);
        return -1;
    }
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, c, ctx_error, ctx_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    if (!info) {
        snprintf(c->why, (size_t)c->why_size, "%s: out of memory", c->path);
        png_destroy_read_struct(&png, NULL, NULL);
        return -1;
    }
    int rc = -1;
    if (setjmp(png_jmpbuf(png)) == 0)
        rc = read_body(png, info, c, w, h, depth, channels);
    png_destroy_read_struct(&png, &info, NULL);
    return rc;
}

int meso_png_read_channel0_fp(FILE* fp, const char* name, uint64_t max_bytes, unsigned extra_per_pixel,
                              uint16_t** values, int* width, int* height, int* bit_depth, uint64_t* need, char* why,
                              int why_size)
{
    *values = NULL;
    png_ctx ctx = {.why = why, .why_size = why_size, .path = name, .fp = fp, .max_bytes = max_bytes,
                   .extra = extra_per_pixel};
    png_ctx* c = &ctx;
    int w = 0, h = 0, depth = 0, channels = 0;
    int rc = read_rows(c, &w, &h, &depth, &channels);
    if (rc == -2 && need)
        *need = c->need;
    uint16_t* out = rc == 0 ? malloc(sizeof(uint16_t) * (size_t)w * (size_t)h) : NULL;
    if (rc == 0 && !out) {
        snprintf(why, (size_t)why_size, "%s: out of memory", name);
        rc = -1;
    }
    if (rc == 0) {
        const size_t stride = (size_t)channels * (size_t)(depth / 8);
        for (size_t y = 0; y < (size_t)h; ++y) {
            const uint8_t* row = c->rows[y];
            for (size_t x = 0; x < (size_t)w; ++x)
                out[y * (size_t)w + x] = depth == 16 ? (uint16_t)(row[x * stride] << 8 | row[x * stride + 1])
                                                     : row[x * stride];
        }
        *values = out;
        *width = w;
        *height = h;
        *bit_depth = depth;
    }
    ctx_free(c);
    return rc;
}

int meso_png_read_rgba8_fp(FILE* fp, const char* name, uint64_t max_bytes, unsigned extra_per_pixel, uint8_t** rgba,
                           int* width, int* height, uint64_t* need, char* why, int why_size)
{
    *rgba = NULL;
    png_ctx ctx = {.why = why, .why_size = why_size, .path = name, .fp = fp, .max_bytes = max_bytes,
                   .extra = extra_per_pixel + 2, .rgba8 = 1}; /* read_body counts 2 B of samples, the copy takes 4 */
    png_ctx* c = &ctx;
    int w = 0, h = 0, depth = 0, channels = 0;
    int rc = read_rows(c, &w, &h, &depth, &channels);
    if (rc == -2 && need)
        *need = c->need;
    if (rc == 0 && (depth != 8 || channels != 4)) {
        snprintf(why, (size_t)why_size, "%s: unsupported PNG layout (%d-bit, %d channels after expansion)", name,
                 depth, channels);
        rc = -1;
    }
    uint8_t* out = rc == 0 ? malloc(4 * (size_t)w * (size_t)h) : NULL;
    if (rc == 0 && !out) {
        snprintf(why, (size_t)why_size, "%s: out of memory", name);
        rc = -1;
    }
    for (size_t y = 0; rc == 0 && y < (size_t)h; ++y)
        memcpy(out + 4 * (size_t)w * y, c->rows[y], 4 * (size_t)w);
    if (rc == 0) {
        *rgba = out;
        *width = w;
        *height = h;
    }
    ctx_free(c);
    return rc;
}

static int write_body(png_structp png, png_infop info, png_ctx* c, const uint16_t* values, int width, int height,
                      int bit_depth)
{
    png_init_io(png, c->fp);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, bit_depth, PNG_COLOR_TYPE_GRAY,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    const size_t bpp = (size_t)bit_depth / 8;
    c->pixels = malloc(bpp * (size_t)width);
    if (!c->pixels) {
        snprintf(c->why, (size_t)c->why_size, "%s: out of memory", c->path);
        return -1;
    }
    for (size_t y = 0; y < (size_t)height; ++y) {
        for (size_t x = 0; x < (size_t)width; ++x) {
            const uint16_t v = values[y * (size_t)width + x];
            if (bpp == 2) {
                c->pixels[2 * x] = (uint8_t)(v >> 8);
                c->pixels[2 * x + 1] = (uint8_t)(v & 0xFF);
            } else {
                c->pixels[x] = (uint8_t)v;
            }
        }
        png_write_row(png, c->pixels);
    }
    png_write_end(png, NULL);
    return 0;
}

int meso_png_write_gray(const char* path, const uint16_t* values, int width, int height, int bit_depth, char* why,
                        int why_size)
{
    if (width <= 0 || height <= 0 || (bit_depth != 8 && bit_depth != 16)) {
        snprintf(why, (size_t)why_size, "%s: bad image size or bit depth", path);
        return -1;
    }
    png_ctx ctx = {.why = why, .why_size = why_size, .path = path};
    png_ctx* c = &ctx;
    c->fp = fopen(path, "wb");
    if (!c->fp) {
        snprintf(why, (size_t)why_size, "%s: can not create", path);
        return -1;
    }
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, c, ctx_error, ctx_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    int rc = -1;
    if (!info)
        snprintf(why, (size_t)why_size, "%s: out of memory", path);
    else if (setjmp(png_jmpbuf(png)) == 0)
        rc = write_body(png, info, c, values, width, height, bit_depth);
    png_destroy_write_struct(&png, &info);
    if (c->fp && fclose(c->fp) != 0 && rc == 0) {
        snprintf(why, (size_t)why_size, "%s: write failed", path);
        rc = -1;
    }
    c->fp = NULL;
    ctx_free(c);
    return rc;
}

/* >>memory ----------------------------------------------------------------
 * PNG files held in memory (embedded in a glTF binary, and read back from
 * one by the tests); the simplified API, 8 bits a channel. */

int meso_png_encode_memory(const uint8_t* px, int width, int height, int channels, int flip_y, uint8_t** out,
                           size_t* size, char* why, int why_size)
{
    *out = NULL;
    *size = 0;
    if (channels < 1 || channels > 4 || width < 1 || height < 1) {
        snprintf(why, (size_t)why_size, "bad image shape %dx%dx%d", width, height, channels);
        return -1;
    }
    static const png_uint_32 formats[4] = {PNG_FORMAT_GRAY, PNG_FORMAT_GA, PNG_FORMAT_RGB, PNG_FORMAT_RGBA};
    png_image img;
    memset(&img, 0, sizeof(img));
    img.version = PNG_IMAGE_VERSION;
    img.width = (png_uint_32)width;
    img.height = (png_uint_32)height;
    img.format = formats[channels - 1];
    const png_int_32 row = (png_int_32)(channels * width);
    const png_int_32 stride = flip_y ? -row : row;
    png_alloc_size_t n = 0;
    if (!png_image_write_to_memory(&img, NULL, &n, 0, px, stride, NULL)) {
        snprintf(why, (size_t)why_size, "%s", img.message);
        return -1;
    }
    uint8_t* buf = malloc(n ? n : 1);
    if (!buf) {
        snprintf(why, (size_t)why_size, "out of memory for a %dx%d PNG", width, height);
        return -1;
    }
    if (!png_image_write_to_memory(&img, buf, &n, 0, px, stride, NULL)) {
        snprintf(why, (size_t)why_size, "%s", img.message);
        free(buf);
        return -1;
    }
    *out = buf;
    *size = (size_t)n;
    return 0;
}

int meso_png_decode_memory_rgba8(const uint8_t* data, size_t size, uint8_t** rgba, int* width, int* height, char* why,
                                 int why_size)
{
    *rgba = NULL;
    png_image img;
    memset(&img, 0, sizeof(img));
    img.version = PNG_IMAGE_VERSION;
    if (!png_image_begin_read_from_memory(&img, data, size)) {
        snprintf(why, (size_t)why_size, "%s", img.message);
        return -1;
    }
    img.format = PNG_FORMAT_RGBA;
    if (img.width == 0 || img.height == 0 || img.width > 65536 || img.height > 65536) {
        snprintf(why, (size_t)why_size, "unsupported size %ux%u", img.width, img.height);
        png_image_free(&img);
        return -1;
    }
    uint8_t* buf = malloc(PNG_IMAGE_SIZE(img));
    if (!buf) {
        snprintf(why, (size_t)why_size, "out of memory");
        png_image_free(&img);
        return -1;
    }
    if (!png_image_finish_read(&img, NULL, buf, 0, NULL)) {
        snprintf(why, (size_t)why_size, "%s", img.message);
        free(buf);
        return -1;
    }
    *rgba = buf;
    *width = (int)img.width;
    *height = (int)img.height;
    return 0;
}
