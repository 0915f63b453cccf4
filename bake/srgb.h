/*
 * srgb.h — the sRGB transfer function (IEC 61966-2-1) both ways, for the
 * bakes that average or scale stored RGBA8 colours in linear light
 * (internal; shell_color.c, mesh_colour_grid.c, cells_levels.c).
 */
#ifndef MESO_SRGB_H
#define MESO_SRGB_H

#include <math.h>

/* Stored value x in [0, 1] to linear light. */
static inline double meso_srgb_to_linear(double x)
{
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

/* A stored 8-bit value to linear light. */
static inline double meso_srgb8_to_linear(unsigned char b) { return meso_srgb_to_linear(b / 255.0); }

/* Linear light (clamped to [0, 1]) to the stored value in [0, 1]. */
static inline double meso_linear_to_srgb(double l)
{
    l = l < 0 ? 0 : l > 1 ? 1 : l;
    return l <= 0.0031308 ? 12.92 * l : 1.055 * pow(l, 1 / 2.4) - 0.055;
}

#endif /* MESO_SRGB_H */
