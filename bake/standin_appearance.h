/*
 * standin_appearance.h — what a mesh stand-in shows (FORMAT.md §7.3 VCOL;
 * issue 14: "the plain base mesh with baked normal/colour", "the base mesh
 * with baked appearance"): per vertex of a stand-in level, the albedo and
 * occlusion the finer surface shows over that vertex's part of the level
 * (internal, mesoi_ prefix). A kind says what its level 0 shows at a point
 * of the base stand-in (an appearance); standin_appearance.c averages it per
 * vertex and carries it to the simplified levels.
 */
#ifndef MESO_STANDIN_APPEARANCE_H
#define MESO_STANDIN_APPEARANCE_H

#include <stdint.h>

#include "meso_bake.h"
#include "triangle_grid.h"

/* What level 0 shows at point p of triangle t of the base stand-in
 * (barycentrics b of its corners): out[0..2] the linear albedo, out[3] the
 * occlusion (the factor the kind's shading darkens its albedo by, 1 for
 * none; negative: nothing is drawn there, the point is left out of the
 * means); with `normals` set, out[4..6] the unit normal of the surface
 * level 0 draws there (object space; zero where it has none). out arrives
 * zeroed. `grid`: this thread's copy of `a->grid` (private query stamps), or
 * NULL when a->grid is NULL. Called from several threads at once. */
typedef struct mesoi_appearance mesoi_appearance;
struct mesoi_appearance {
    void (*at)(const mesoi_appearance* a, mesoi_tri_grid* grid, uint32_t t, const double b[3], const double p[3],
               float out[7]);
    const mesoi_tri_grid* grid; /* a grid `at` queries, or NULL */
    const void* ctx;
    int subdivisions;           /* the most sub-triangles along an edge (below); 0: 4 */
    int occlusion_only;         /* 1: level 0 shows the draw's albedo (no colour of its own), darkened by
                                   the occlusion: VCOL holds the occlusion alone (U8 x 1) */
    int normals;                /* 1: `at` gives level 0's normal too (a shell: shell_color.h) */
};

/* Per vertex of `m`, what `a` shows around it (4 floats per vertex, as
 * `at` gives them): with w_v(x) the vertex's hat function (its barycentric
 * weight on the triangles around it), occlusion A = ∫ w_v occ dA / ∫ w_v dA
 * and albedo C = ∫ w_v albedo occ dA / ∫ w_v occ dA, so that C A, what the
 * mesh shader multiplies, is the mean of the kind's albedo × occlusion. The
 * integrals are sums over the centroids of n² equal sub-triangles of each
 * triangle, n = its longest edge / `spacing` rounded up, 1 to
 * a->subdivisions (an appearance that is cheap to ask takes more), and to
 * about 2^17 samples for the level (but not below 2; a simplified level:
 * 2^15, not below 1). With
 * source_grid non-NULL (a grid over the base stand-in), `m` is a
 * simplified level: each of its points takes what `a` shows at the nearest
 * point of the base stand-in. threads <= 0: all cores; the result does not
 * depend on it.
 * `normals` (3 floats per vertex; NULL: not wanted; needs a->normals): the
 * stand-in's baked normal, N = ∫ w_v n dA normalised (n level 0's unit
 * normal: the way the vertex's part of the surface faces as a whole, what
 * a vertex normal can hold of a relief finer than the stand-in), or the
 * mesh's own normal where no sample gave one. */
meso_result mesoi_vertex_appearance(const meso_mesh* m, double spacing, const mesoi_appearance* a,
                                    const mesoi_tri_grid* source_grid, int threads, float* shows, float* normals,
                                    meso_error* err);

/* The same as VCOL stores it (FORMAT.md §7.3): components 4, RGBA8 (rgb
 * the sRGB encoding of the albedo, a 255 × the occlusion); components 1,
 * the occlusion byte alone. */
void mesoi_appearance_encode(const float* shows, uint32_t vertex_count, int components, uint8_t* out);

#endif /* MESO_STANDIN_APPEARANCE_H */
