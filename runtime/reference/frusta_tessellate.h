/*
 * frusta_tessellate.h — a triangle mesh of a frusta object's surface: the
 * polygon baseline of relief-mapped-conical-frusta.md §4 (its Figure 6:
 * "at least 256k polygons are necessary to achieve similar quality to ray
 * casting"), and what `mesoinspect export` writes for a frusta object. Each
 * frustum's relief surface (FORMAT.md §7.2 kind 4, w = h(s, t)) is sampled
 * on a regular (u, v) grid and triangulated, balls as latitude–longitude
 * spheres, flagged caps as fans.
 *
 * The grid point (u, v) of a frustum lies on the parallel cone r(y) + h D
 * through it: angle φ = 2π (u + u_offset − v·twist/2π) around the axis, and
 * the axial coordinate y = y0 + v (y1 − y0) between where that cone's
 * generator meets the two planes — the exact inverse of the reference's
 * (u, v) (frustum_reference.h), so a finer grid converges to the surface
 * the reference renders. h is the reference's bilinear, wrapping height
 * (meso_ref_texfn_value). Normals are central differences of the grid
 * (outward). Neighbouring frusta meet at the joint plane along the same
 * curve, but their grids do not share vertices (u frames agree at one point
 * only), so a coarse tessellation can show hairline cracks there, as it
 * would in an engine.
 *
 * The tessellation itself is formats/frusta_tessellation.c (the baker's
 * mesh stand-in level uses it too); these are its grid rule and the
 * reference's relief sampler. Not part of libmeso: the benchmarks
 * (tests/bench/bench_frusta_render.c) and mesoinspect use it, beside the
 * references.
 */
#ifndef MESO_FRUSTA_TESSELLATE_H
#define MESO_FRUSTA_TESSELLATE_H

#include <stdint.h>

#include "frusta_pose.h"
#include "frusta_tessellation.h"
#include "shell_map.h"

#ifdef __cplusplus
extern "C" {
#endif

/* An indexed triangle mesh (malloc'd arrays; free with meso_ref_tess_free). */
typedef meso_frusta_tess_mesh meso_ref_tess_mesh;

/* Largest grid the tessellation takes (nu), so every count fits in 32 bits
 * for any sane object. */
#define MESO_REF_TESS_MAX_GRID 4096u

/* The whole object: per frustum an nu × nv grid (plus caps) with nv chosen
 * so grid cells cover as much relief texture along v as across u
 * (nv = ⌈nu · v_scale / u_scale⌉, at least 2, at most 64 nu), per ball an
 * nu × nu/2 sphere. `relief` is the object's height field (kind 1), or
 * NULL / kind 0 for none (frusta with relief_depth 0 ignore it too).
 * Returns 1, or 0 (nothing allocated) when nu is 0 or above
 * MESO_REF_TESS_MAX_GRID, a count would not fit in 32 bits, or memory runs
 * out (never for a frustum's proportions). */
int meso_ref_frusta_tessellate(const meso_frustum_rec* recs, uint32_t count, const meso_frustum_ball_rec* balls,
    uint32_t ball_count, const meso_ref_texfn* relief, uint32_t nu, meso_ref_tess_mesh* out);

/* Surface point of frustum f at grid coordinates (u, v) ∈ [0, 1]², with the
 * relief displacement (above). */
void meso_ref_tess_point(const meso_frustum_rec* f, const meso_ref_texfn* relief, double u, double v, double p[3]);

void meso_ref_tess_free(meso_ref_tess_mesh* m);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FRUSTA_TESSELLATE_H */
