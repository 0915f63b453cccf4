/*
 * make_binary_parts.c — writes the two binary parts make_gltf.py embeds in
 * the glTF test inputs, which Python alone cannot make here:
 *   box_draco.drc  a closed box (8 vertices, 12 triangles, uvs) compressed
 *                  by the project's own Draco adapter (meso_draco_encode,
 *                  sequential connectivity: vertex order kept);
 *   texture.jpg    a 4 x 4 RGB JPEG (libjpeg, quality 100) of the colours
 *                  the PNG texture has, for the .glb's base-colour texture.
 * Build and run from the repository root (tests/data/gltf/README.md).
 */
#include <stdio.h>
#include <stdlib.h>

#include <jpeglib.h>

#include "adapters.h"

static const float box_xyz[8 * 3] = {
    -0.5f, -0.5f, -0.5f, 0.5f, -0.5f, -0.5f, 0.5f, 0.5f, -0.5f, -0.5f, 0.5f, -0.5f,
    -0.5f, -0.5f, 0.5f,  0.5f, -0.5f, 0.5f,  0.5f, 0.5f, 0.5f,  -0.5f, 0.5f, 0.5f,
};
static const float box_uv[8 * 2] = {0, 0, 1, 0, 1, 1, 0, 1, 0, 0, 1, 0, 1, 1, 0, 1};
/* counter-clockwise seen from outside */
static const uint32_t box_tri[12 * 3] = {
    0, 3, 2, 0, 2, 1, /* -z */
    4, 5, 6, 4, 6, 7, /* +z */
    0, 1, 5, 0, 5, 4, /* -y */
    3, 7, 6, 3, 6, 2, /* +y */
    0, 4, 7, 0, 7, 3, /* -x */
    1, 2, 6, 1, 6, 5, /* +x */
};

int main(void)
{
    meso_mesh m = {8, 12, (float*)box_xyz, NULL, (float*)box_uv, (uint32_t*)box_tri, NULL};
    meso_draco_options opt = {14, 10, 12, 7};
    void* data = NULL;
    size_t size = 0;
    meso_error err = {0};
    if (meso_draco_encode(&m, &opt, &data, &size, &err) != MESO_OK) {
        fprintf(stderr, "draco: %s\n", err.message);
        return 1;
    }
    FILE* f = fopen("tests/data/gltf/box_draco.drc", "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0)
        return 1;
    free(data);

    /* the PNG's texels (make_gltf.py TEXELS): row-major, top row first */
    static const unsigned char rgb[4 * 4 * 3] = {
        200, 40, 40,  200, 40, 40,  40, 200, 40,  40, 200, 40,  200, 40, 40,  200, 40, 40,  40, 200, 40,  40, 200, 40,
        40, 40, 200,  40, 40, 200,  220, 220, 40, 220, 220, 40, 40, 40, 200,  40, 40, 200,  220, 220, 40, 220, 220, 40,
    };
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr jerr;
    c.err = jpeg_std_error(&jerr);
    jpeg_create_compress(&c);
    FILE* j = fopen("tests/data/gltf/texture.jpg", "wb");
    if (!j)
        return 1;
    jpeg_stdio_dest(&c, j);
    c.image_width = 4;
    c.image_height = 4;
    c.input_components = 3;
    c.in_color_space = JCS_RGB;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 100, TRUE);
    jpeg_start_compress(&c, TRUE);
    for (int y = 0; y < 4; ++y) {
        JSAMPROW row = (JSAMPROW)(rgb + 12 * y);
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    return fclose(j) != 0;
}
