/* bake_shell.h — the texture function of a shell bake (bake_shell_texture.c),
 * shared with the pipeline in bake_shell.c: the sampled function, its
 * distance map, and texture coordinates per output vertex (FORMAT.md §7.2,
 * "Shell prisms and texture space"). Internal. */
#ifndef MESO_BAKE_SHELL_H
#define MESO_BAKE_SHELL_H

#include "bake_internal.h"
#include "distance_map.h"
#include "height_field_levels.h"
#include "texture_function.h"

typedef struct mesoi_shell_texture {
    meso_texfn fn;
    meso_distmap dist;
    const char* dist_type; /* "u8", "u16" or "f32" */
    float* uvs;            /* 2 per output vertex: texture coordinates, tiling included */
    const char* uv_source; /* "mesh" or "planar" */
    char plane[3];         /* planar: the two axes, e.g. "xz" (s along the first) */
    /* Split at uv seams (a mesh with corner uvs), else 0, NULL, NULL. */
    uint32_t seam_vertices; /* copies added: the output has the mesh's vertices plus these */
    uint32_t* source;       /* each output vertex's mesh vertex */
    uint32_t* indices;      /* 3 * triangle_count: the triangles over the output vertices */
    /* Animated (options frames > 0): every frame's TX3D and DIST payloads,
     * frame k at k * the frame's size (frame 0 is fn and dist); else NULL. */
    uint8_t* fn_frames;
    uint8_t* dist_frames;
    /* Native coarser levels (height_field_levels.h, volume_levels.h): a
     * static height field or volume halved, lod 1..native_count; none for
     * frames or --levels < 3. */
    mesoi_height_level native[MESOI_HEIGHT_MAX_NATIVE];
    uint32_t native_count;
} mesoi_shell_texture;

void mesoi_shell_texture_free(mesoi_shell_texture* tx);
/* Parse the spec, sample the function, bake its distance map (stage lines
 * "texture" and "distance map"). */
meso_result mesoi_shell_texture_prepare(mesoi_bake_run* run, const meso_bake_shell_options* o,
                                        mesoi_shell_texture* tx, meso_error* err);
/* Texture coordinates: the mesh's own times the tiling (split at seams when
 * the mesh has per-corner uvs), or (documented fallback, with a warning) a
 * planar projection onto the two largest bounding-box extents. */
meso_result mesoi_shell_texture_uvs(mesoi_bake_run* run, const meso_bake_shell_options* o, const meso_mesh* m,
                                    const double lo[3], const double hi[3], mesoi_shell_texture* tx,
                                    meso_error* err);
/* META.parameters.texture and the report's "texture". */
void mesoi_shell_texture_json(cJSON* parent, const meso_bake_shell_options* o, const mesoi_shell_texture* tx,
                              int report);

#endif
