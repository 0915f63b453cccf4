/*
 * export.h — internal to `mesoinspect export` (export.c: the command and
 * one glTF primitive per object; export_shell_maps.c: a shell's baked
 * normal and base-colour maps; glb_write.c: the GLB container).
 */
#ifndef MESO_INSPECT_EXPORT_H
#define MESO_INSPECT_EXPORT_H

#include <stddef.h>
#include <stdint.h>

#include "meso_file.h"
#include "shell_map.h"

/* The runtime's default albedo (meso_rt_draw_desc.albedo all zero), linear
 * RGB: what libmeso draws every object kind without its own colour in. */
#define MI_DEFAULT_ALBEDO_R 0.80f
#define MI_DEFAULT_ALBEDO_G 0.74f
#define MI_DEFAULT_ALBEDO_B 0.66f

/* One object as one glTF node, mesh, primitive and material. Arrays are
 * malloc'd and owned (mi_glb_prim_free). */
typedef struct mi_glb_prim {
    char name[32];           /* the object's name: node and mesh name */
    uint32_t vertex_count;
    uint32_t index_count;    /* 0: no indices; the primitive is then POINTS */
    float* positions;        /* 3 per vertex, finite */
    float* normals;          /* 3 per vertex, unit; or NULL */
    float* tangents;         /* 4 per vertex (xyz unit, w = ±1); or NULL */
    float* uvs;              /* 2 per vertex, glTF's (u, v): v = 1 − t'; or NULL */
    float* uvs1;             /* TEXCOORD_1, 2 per vertex, same v flip; or NULL */
    float* colors;           /* COLOR_0, 3 per vertex, linear RGB in [0, 1]; or NULL */
    int color_texcoord;      /* baseColorTexture.texCoord: 0, or 1 (needs uvs1) */
    uint32_t* indices;       /* index_count, each < vertex_count */
    float base_color[4];     /* pbrMetallicRoughness.baseColorFactor, linear */
    uint8_t* color_png;      /* base-colour texture (sRGB), or NULL */
    size_t color_png_size;
    uint8_t* normal_png;     /* tangent-space normal texture, or NULL (needs normals, tangents, uvs) */
    size_t normal_png_size;
} mi_glb_prim;

void mi_glb_prim_free(mi_glb_prim* p);

/* The GLB file of `count` primitives, one scene with one node each, in
 * order: *out (malloc'd) gets *size bytes. `generator` is asset.generator.
 * MESO_ERR_OUT_OF_MEMORY, or MESO_ERR_UNSUPPORTED when the buffer would
 * pass the 4 GiB a GLB chunk can hold (err names what). */
meso_result mi_glb_write(const mi_glb_prim* prims, uint32_t count, const char* generator, uint8_t** out, size_t* size,
                         meso_error* err);

/* >>shell maps (export_shell_maps.c) ---------------------------------------- */

/* What the shell maps are made from: the base mesh as exported (glTF uvs,
 * unit normals), each vertex's prism height |top − bottom|, the texture
 * function and an optional COLR chunk (RGBA8, W × H × D, sRGB). */
typedef struct mi_shell_src {
    const float* positions;  /* 3 per vertex */
    const float* normals;    /* 3 per vertex, unit */
    const float* uvs;        /* 2 per vertex, glTF (s, 1 − t') */
    const float* heights;    /* prism height per vertex */
    const uint32_t* indices; /* 3 per triangle */
    uint32_t vertex_count, triangle_count;
    const meso_ref_texfn* tex;   /* kind 0 none, 1 height field, 2 density volume */
    const uint8_t* colr;         /* RGBA8 or NULL */
    uint32_t colr_dims[3];
    uint32_t colr_mapping;       /* the CMAP record's: MESO_CMAP_TILED or MESO_CMAP_BASE */
} mi_shell_src;

/* k = prism height / (object length per unit of texture space): the
 * median over triangles of each triangle's mean prism height over
 * sqrt(object area / uv area); triangles with a uv area under 1e-12 are
 * skipped (0 when none is left). */
double mi_shell_slope_scale(const mi_shell_src* s);

/* Per-vertex tangents (4 floats each, malloc'd into *out) from the uv
 * parametrisation: xyz along increasing u, made perpendicular to the normal,
 * w = +1 when cross(normal, tangent) points along decreasing glTF v (glTF's
 * +Y of a normal texture, "up" in the image), else −1. MESO_ERR_OUT_OF_MEMORY. */
meso_result mi_shell_tangents(const mi_shell_src* s, float** out);

/* The tile's normal map and base-colour map as PNGs (a BASE-mapped COLR:
 * the COLR itself, an image of the base mesh's uv square) (normal_png NULL when
 * the shell has no texture function; color_png NULL when it has neither a
 * texture function nor a COLR). `k` is mi_shell_slope_scale's. Returns 0,
 * or -1 with a reason in `why`. */
int mi_shell_maps(const mi_shell_src* s, double k, uint8_t** normal_png, size_t* normal_size, uint8_t** color_png,
                  size_t* color_size, char* why, int why_size);

/* sRGB transfer (IEC 61966-2-1) of a linear value in [0, 1], to 0..255. */
uint8_t mi_srgb8(double linear);
/* Its inverse for an 8-bit sRGB value. */
double mi_srgb_to_linear(uint8_t c);

#endif
