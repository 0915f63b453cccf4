/*
 * frusta_standin.h — the coarse end of a frusta object's levels of detail
 * (FORMAT.md §7.10, form MESO_LEVEL_MESH): the object as a triangle mesh,
 * drawn where a relief-mapped frustum covers too few pixels to be worth
 * its ray march (relief-mapped-conical-frusta.md §4, Figure 6: polygons
 * win where their count is small; issue 14: "at coarse error a polygon
 * tessellation"), with an error bound measured in the bake.
 *
 * The mesh is formats/frusta_tessellation.c's grid of every frustum, cap
 * and ball, taken at the MID-RELIEF cone: the relief height is replaced by
 * the constant h_m = (h_min + h_max) / 2 of the stored texels (bilinear
 * interpolation never leaves [h_min, h_max]). Decided: the relief is not
 * baked into the vertices — a grid of a few cells per frustum cannot follow
 * texel-sized relief, sampled heights alias, and the bound could then only
 * be the whole depth D (h_max − h_min); the mid cone halves it.
 *
 * Error (object units, two-sided, as §7.10 asks), the sum of three terms,
 * each a bound through the same correspondence (u, v) ↔ (u, v), which maps
 * each surface onto the other (so it bounds both directions of the
 * Hausdorff distance):
 *  1. relief: the native point p(u, v, δ), δ = D h(s, t), against the mid
 *     cone's p(u, v, δ_m). For a fixed (u, v) the point is affine in δ
 *     (frusta_tessellation.h): p(δ) = p(0) + δ g(u, v), so the distance is
 *     |δ − δ_m| |g| ≤ D (h_max − h_min) / 2 · |g|. g is affine in v, so
 *     |g| is largest at v = 0 or 1, where g lies in the end's plane:
 *     g = w + c (a + k w), |g|² = (1 + c k)² + c², c = −(n·w) / (n·a +
 *     k n·w) (n the plane's normal, a the axis, k the radius slope, w ⟂ a
 *     the radial direction); c is monotone in n·w ∈ [−β, β], β = |n − (n·a)
 *     a|, and |g|² convex in c, so the largest |g| of an end is at n·w = ±β:
 *     G_f, exact, per frustum. A tilted plane lets the cut slide along the
 *     plane as the relief rises: G_f = 1 for a perpendicular cut. Caps
 *     (centre + v (rim − centre)) move by v g ≤ G_f; the walls the native
 *     level shows at joints where two reliefs differ are points
 *     p(u, e, δ) with δ between them, so the same bound covers them. Balls
 *     have no relief.
 *  2. chord: the grid's triangles against the mid cone's surface at the
 *     same (u, v). On a triangle where the surface is quadratic in (u, v),
 *     the difference is the quadratic 4 Σ m_ij λ_i λ_j, m_ij its value at
 *     the edge midpoints, so at most 4/3 max |m_ij| (Σ λ_i λ_j ≤ 1/3); the
 *     tessellation measures max |m_ij| over every edge of every lateral
 *     and ball grid (edge_sag). A cap is a convex plane region (a convex
 *     cone's cut) fanned from its centre to the lateral grid's rim points:
 *     its points and the fan's are within the rim edges' sag of each other
 *     (between a chord and its arc), which the lateral grid measured. Higher-order terms are left out: they are O(cell³) and the
 *     grids below are chosen so cells turn at most ~π/3 of a turn.
 *  3. rounding: vertices stored as f32, ≤ 2⁻²³ of the largest coordinate
 *     magnitude.
 * The sum is rounded up to f32. tests/integration/test_frusta_standin.c
 * checks it against the exact reference's hits, both ways.
 *
 * Density (the cells per part), from a chord target e_t = max(relief term,
 * 0.5 % of the bounding-box diagonal): around a part of largest radius R,
 * nu = ⌈π / acos(1 − ¾ e_t / R)⌉ cells (the arc sagitta R (1 − cos(π/nu))
 * ≤ ¾ e_t, so 4/3 of it ≤ e_t), at least 3 (4 for balls, even), at most
 * 256; along the axis one cell (a generator is straight) unless the frustum
 * twists, then ⌈|twist| nu / 2π⌉ so a cell turns no more along v than
 * across u, or tapers: a cell's diagonal midpoint lies about
 * Δr / nv · sin(π / nu) / 2 beside the surface point of its (u, v) (Δr the
 * radius change), which term 2 counts, so nv ≥ Δr sin(π / nu) / (1.5 e_t). Degenerate triangles (cap centres, ball poles) are dropped;
 * a vertex whose grid normal degenerates takes its triangles' mean normal.
 */
#ifndef MESO_FRUSTA_STANDIN_H
#define MESO_FRUSTA_STANDIN_H

#include "color_map.h"
#include "frusta_chunks.h"
#include "meso_bake.h"
#include "standin_appearance.h"
#include "texture_function.h"

typedef struct meso_frusta_standin {
    meso_mesh mesh;        /* positions, normals, indices (malloc'd; meso_frusta_standin_free) */
    double error;          /* the stated error: relief + chord + rounding */
    double relief_error, chord_error;
    double relief_gain;    /* max over the frusta with a relief of depth x G_f (term 1): a height change dh
                              at a relief coordinate moves the surface there by at most dh x this */
    uint32_t nu_min, nu_max; /* cells around, over the frusta */
    float bbox_min[3], bbox_max[3];
    uint32_t* owner;       /* per mesh vertex: the tessellation's (frusta_tessellation.h) */
    float* uv;             /* per mesh vertex: its (u, v), 2 each, the tessellation's */
} meso_frusta_standin;

/* The stand-in of `obj`; `relief` is the object's height field (the stored
 * texels decide h_min, h_max) or NULL. MESO_ERR_UNSUPPORTED (nothing made)
 * when a plane is so tilted that the relief term has no bound (its cut runs
 * parallel to a generator); the caller then writes one level. */
meso_result meso_frusta_standin_build(const meso_frusta_object* obj, const meso_texfn* relief,
    meso_frusta_standin* out, meso_error* err);

void meso_frusta_standin_free(meso_frusta_standin* s);

/* Lowest and highest stored texel of a height field, normalised (1 and 0
 * without texels). */
void meso_frusta_height_range(const meso_texfn* t, double* lo, double* hi);

/* What level 0 of `obj` shows on the stand-in `st` and its simplifications
 * (standin_appearance.h), as frusta_frag.glsl shades a hit: a frustum's
 * point shows the colour map bilinear (wrapping, in linear light) at the
 * relief coordinates (s, t) = (u u_scale, v_offset + v v_scale) of its
 * (u, v), with occlusion 0.25 + 0.75 h(s, t) on a frustum with a relief
 * (1 without); a cap's point the colour at its end, occlusion 0.25 on a
 * relief frustum (it lies below the relief layer, w < 0) and 1 without; a
 * ball the map's mean colour, occlusion 1. `color` NULL (a relief without a colour map): level 0 shows
 * the draw's albedo darkened by the relief's occlusion, and `out` says the
 * occlusion alone (occlusion_only; bake_frusta.c does not use it, why is
 * said there). `ctx` is filled here and borrowed by `out` with the rest. */
typedef struct meso_frusta_colours {
    const meso_frusta_object* obj;
    const meso_frusta_standin* st;
    const meso_texfn* relief; /* NULL: none */
    const meso_color_map* color; /* NULL: none */
    float mean[3];            /* the map's mean linear colour */
} meso_frusta_colours;
void meso_frusta_standin_appearance(const meso_frusta_object* obj, const meso_frusta_standin* st,
    const meso_texfn* relief, const meso_color_map* color, meso_frusta_colours* ctx, mesoi_appearance* out);

#endif /* MESO_FRUSTA_STANDIN_H */
