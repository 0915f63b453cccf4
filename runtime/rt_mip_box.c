/*
 * rt_mip_box.c — the next mip level of a texture by a box filter on the
 * host, for the formats glGenerateMipmap cannot take: OpenGL ES generates
 * levels only for formats that are both colour-renderable and filterable,
 * which R16 (GL_EXT_texture_norm16), R16F and R32F are not everywhere
 * (rt_common.c upload_image says which formats go through here).
 *
 * Level sizes follow OpenGL: each axis halves, rounded down, never below 1
 * (OpenGL 4.6 §8.14.3). A texel of the coarser level is the mean of the
 * 2 x 2 (x 2) texels below it, as glGenerateMipmap's box filter does for
 * even sizes; where an axis is odd, its last fine texel has no coarse texel
 * of its own and is left out (the specification leaves the filter of
 * non-power-of-two levels to the implementation), and where an axis is
 * already 1 the pair collapses onto the one texel. Integer texels round to
 * nearest; the mean of normalised values is the normalised mean.
 */
#include "rt_internal.h"

#include <string.h>

uint32_t mesoi_mip_size(uint32_t n, int level)
{
    for (int l = 0; l < level && n > 1; ++l)
        n /= 2;
    return n;
}

int mesoi_mip_levels(const uint32_t dims[3], int dims3)
{
    uint32_t m = dims[0] > dims[1] ? dims[0] : dims[1];
    if (dims3 && dims[2] > m)
        m = dims[2];
    int levels = 1;
    while (m > 1) {
        m /= 2;
        ++levels;
    }
    return levels;
}

static double texel(const void* data, GLenum type, size_t i)
{
    switch (type) {
    case GL_UNSIGNED_BYTE: return ((const uint8_t*)data)[i];
    case GL_UNSIGNED_SHORT: return ((const uint16_t*)data)[i];
    default: return ((const float*)data)[i];
    }
}

static void store(void* data, GLenum type, size_t i, double v)
{
    switch (type) {
    case GL_UNSIGNED_BYTE: ((uint8_t*)data)[i] = (uint8_t)(v + 0.5); break;
    case GL_UNSIGNED_SHORT: ((uint16_t*)data)[i] = (uint16_t)(v + 0.5); break;
    default: ((float*)data)[i] = (float)v; break;
    }
}

void mesoi_mip_box(const void* fine, const uint32_t fine_dims[3], int components, GLenum type, void* coarse)
{
    uint32_t cd[3];
    for (int k = 0; k < 3; ++k)
        cd[k] = mesoi_mip_size(fine_dims[k], 1);
    const size_t fx = fine_dims[0], fy = fine_dims[1];
    for (uint32_t z = 0; z < cd[2]; ++z)
        for (uint32_t y = 0; y < cd[1]; ++y)
            for (uint32_t x = 0; x < cd[0]; ++x) {
                /* The fine texels below: 2x, 2x + 1 (the same one on an axis of size 1). */
                const uint32_t x0 = fine_dims[0] > 1 ? 2 * x : 0, x1 = fine_dims[0] > 1 ? 2 * x + 1 : 0;
                const uint32_t y0 = fine_dims[1] > 1 ? 2 * y : 0, y1 = fine_dims[1] > 1 ? 2 * y + 1 : 0;
                const uint32_t z0 = fine_dims[2] > 1 ? 2 * z : 0, z1 = fine_dims[2] > 1 ? 2 * z + 1 : 0;
                const size_t out = ((size_t)z * cd[1] + y) * cd[0] + x;
                for (int c = 0; c < components; ++c) {
                    double sum = 0.0;
                    for (int k = 0; k < 8; ++k) {
                        const size_t xi = (k & 1) ? x1 : x0, yi = (k & 2) ? y1 : y0, zi = (k & 4) ? z1 : z0;
                        sum += texel(fine, type, ((zi * fy + yi) * fx + xi) * (size_t)components + (size_t)c);
                    }
                    store(coarse, type, out * (size_t)components + (size_t)c, sum / 8.0);
                }
            }
}
