/*
 * shell_reference.h — the exact CPU reference for shell rendering: a ray
 * caster of the same mapping as libmeso's GL techniques, in double
 * precision, Φ (or Φ_c) inverted exactly, dense sampling along the
 * world-space ray, the same texture filtering and shading. Slow on purpose;
 * tests and benchmarks measure the GL techniques against it, and
 * `mesoinspect preview --reference` renders with it.
 *
 * Rays and shading — identical in the GLSL (runtime/shaders/shell_*.glsl):
 *  - pixel (x, y), y = 0 at the bottom, centre at ndc
 *    ((2x+1)/W − 1, (2y+1)/H − 1); with M = (proj · view · model)⁻¹ the ray
 *    starts at M·(ndc, −1, 1) (near plane) towards M·(ndc, +1, 1); object space.
 *  - the first point along the ray where the texture function is solid
 *    inside a prism (w ∈ [0,1], u, v, t ≥ 0) is the hit; its depth is
 *    0.5 · z_clip / w_clip + 0.5 of proj·view·model·p.
 *  - normal: g from meso_ref_texfn_gradient at the hit, n = normalize(J⁻ᵀ g),
 *    J = ∂Φ/∂(s,t',w) — Φ_c for curved shells — by central differences in
 *    (u,v,w) with δ = 1e-3, then the (u,v) → (s,t') affine map; n is turned
 *    to face the ray (dot(n, dir) < 0).
 *  - colour = albedo · (0.25 + 0.75 w) · (0.15 + 0.85 max(0, n·l)), l the
 *    light direction in object space (transpose(mat3(model)) · light_dir,
 *    normalised); linear, no gamma. Background: coverage 0, depth 1.
 *    albedo = the shell's colour at the hit's texture point
 *    (meso_ref_color_value, COLR + CMAP) when it has one, else the view's.
 * Prisms come from the shell object's MESH + SDIR chunks (FORMAT.md §7.2).
 */
#ifndef MESO_SHELL_REFERENCE_H
#define MESO_SHELL_REFERENCE_H

#include <stdint.h>

#include "meso_file.h"
#include "shell_map.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct meso_ref_shell {
    uint32_t vertex_count, triangle_count, layers;
    float* positions;  /* 3 per vertex */
    float* directors;  /* 3 per vertex per layer (SDIR layout) */
    float* uvs;        /* 2 per vertex, or NULL (then all zero) */
    uint32_t* indices; /* 3 per triangle */
    meso_ref_texfn tex;    /* values owned here */
    float* tex_values;
    meso_ref_color color;  /* COLR texels owned here (color_texels); w 0: none */
    uint8_t* color_texels;
    float bbox_min[3], bbox_max[3];
} meso_ref_shell;

/* Load a shell object (kind 2) from an open file. */
meso_result meso_ref_shell_load(meso_file* f, uint32_t object_id, meso_ref_shell* out, meso_error* err);
/* The same for level `lod` of a levelled file (FORMAT.md §7.10: per chunk
 * type the smallest lod >= `lod`): a native coarser level's own texture
 * function (bake/height_field_levels.h). meso_ref_shell_load is lod 0. */
meso_result meso_ref_shell_load_level(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_shell* out,
                                      meso_error* err);
void meso_ref_shell_free(meso_ref_shell* s);
/* Animated texture functions (FORMAT.md §7.2): replace the loaded function
 * with the object's stored frame for time t (meso_anim_frame_at), as
 * libmeso's meso_rt_shell_set_time shows it. A shell without an ANIM chunk
 * keeps its function (MESO_OK). */
meso_result meso_ref_shell_set_time(meso_file* f, uint32_t object_id, double t, meso_ref_shell* s, meso_error* err);
/* The prism of triangle f, with uv_scale applied. */
void meso_ref_shell_prism(const meso_ref_shell* s, uint32_t f, double uv_scale, meso_prism* out);

typedef struct meso_ref_view {
    double view[16], proj[16], model[16]; /* column-major; model all zero = identity */
    int width, height;
    double light_dir[3]; /* zero: (0.3, 0.8, 0.5) normalised */
    double albedo[3];    /* zero: (0.80, 0.74, 0.66) */
    int curved;          /* 0: smooth mapping Φ, 1: curved mapping Φ_c */
    double uv_scale;     /* 0 means 1 */
    int samples_per_prism; /* dense samples along each prism's ray interval; 0 means 1024 */
    int threads;           /* 0: all cores (OpenMP); the result never depends on it */
} meso_ref_view;

typedef struct meso_ref_image {
    int width, height;
    float* rgb;        /* 3 per pixel, row 0 at the bottom */
    float* depth;      /* window depth in [0,1], 1 where not covered */
    uint8_t* coverage; /* 1 where the ray hit the surface */
    float* hit;        /* object-space hit point, 3 per pixel (NaN where not covered) */
    float* normal;     /* object-space shading normal n above, 3 per pixel (0 where not covered) */
    float* albedo;     /* linear albedo at the hit, 3 per pixel, as the G-buffer pass writes it (0 where not
                          covered; the kinds that do not fill it leave 0) */
} meso_ref_image;

meso_result meso_ref_render(const meso_ref_shell* s, const meso_ref_view* v, meso_ref_image* out);
void meso_ref_image_free(meso_ref_image* img);

#ifdef __cplusplus
}
#endif
#endif /* MESO_SHELL_REFERENCE_H */
