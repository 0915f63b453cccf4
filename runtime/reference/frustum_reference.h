/*
 * frustum_reference.h — the exact CPU reference for relief-mapped conical
 * frusta (relief-mapped-conical-frusta.md §2–3; FORMAT.md §7.2 kind 4):
 * analytic ray–cone intersection clipped by the segment's two cutting planes
 * (§2.5), the (u, v) parametrisation (§2.3), the cone's normal and the
 * paper's interpolated shading normal (§2.4), and the relief surface (§3)
 * found by dense sampling plus bisection. Double precision, slow on purpose:
 * libmeso's GL ray caster and the benchmarks are measured against it.
 *
 * A segment is a solid: the points p whose axial coordinate
 * y = (p − c0)·a (a the unit axis c0 → c1, h = |c1 − c0|) and radial vector
 * q = p − c0 − y a satisfy
 *     |q| ≤ r(y) = r0 + k y,  k = (r1 − r0)/h,  r(y) ≥ 0     (the cone, eq. 1)
 *     n0·p ≤ d0  and  n1·p ≤ d1                               (its two planes)
 * The radius is written as a linear function of y rather than through the
 * apex height h' of eq. 2, so cylinders (r0 = r1, h' = ∞) need no special
 * case; r(y) ≥ 0 rejects the mirror nappe beyond the apex, which eq. 10's
 * quadratic also finds. The planes' normals point out of the segment
 * (plane 0 at the c0 end, plane 1 at the c1 end).
 *
 * The surface that rays hit is the lateral cone surface inside both planes
 * plus, for an end whose `cap` flag is set, the flat cap (the plane's disc
 * inside the cone). At a joint the cap is off: the neighbour continues the
 * surface. Balls (spheres) close branch points (bake/frustum_model.h).
 *
 * Parametrisation (§2.3), given the frame (x axis `frame_x` ⟂ a; z = x × a):
 *     u = atan2(q·x, q·z) / 2π − u_offset + v · twist / 2π,  wrapped to [0, 1)
 * (the paper's u = atan(x/z)/2π with its quadrant made explicit). v is the
 * ratio (7) along the generator through p of the cone through p — the cone
 * r(y) + δ, δ = |q| − r(y), parallel to the segment's — between that
 * generator's points P0, P1 on the two planes; on a generator the distance
 * ratio equals the ratio of axial coordinates, v = (y − y0)/(y1 − y0).
 * Normals: `normal` is the true outward unit normal of what was hit;
 * `shading_normal` is eq. 8 on the cone through p:
 * normalize((1 − v) N_l + v N_u), N_l = normalize(P0 − c0),
 * N_u = normalize(P1 − c1), c0 and c1 the plane centres (the paper's
 * (0,0,0) and (0,h,0): "normals ... face away from the base and top point
 * of the medial axis"). Caps and balls: the true normal.
 *
 * Relief (§3, FORMAT.md §7.2). A segment with relief_depth D > 0, rendered
 * with a height field, has a shell between its cone (w = 0) and the
 * parallel cone r(y) + D (w = 1), cut by the same planes:
 *     w = (|q| − r(y)) / D,
 *     (s, t) = (u · u_scale, v_offset + v · v_scale)   (u, v of the cone through p),
 *     h(s, t) = the height field, bilinear, texel centres at ((i + ½)/W,
 *               (j + ½)/H), wrapping in s and t (meso_ref_texfn_value, kind 1).
 * The solid is w ≤ h (so the segment's own cone is always solid); the relief
 * surface is w = h. Rays hit the relief surface (entering or leaving, as
 * for plain segments) or the plane's face of the solid at either end,
 * capped or not (part CAP0/CAP1, the plane's normal; decided here, FORMAT.md
 * is silent): at a joint the two reliefs need not agree, and where one
 * stands higher than the other its face is an exposed wall; where both are
 * solid the ray meets the neighbour's relief first, so every end face being
 * a surface gives exactly the union's first hit from outside (the plain
 * rule, open joints, would let rays see into the higher relief from the
 * side: tests/frusta/test_frusta_seams counts those pixels). Balls have no
 * relief.
 *   Search: the ray's interval inside the outer solid (r(y) + D, both
 * planes, right nappe: one interval, the solid is convex) is sampled from
 * its entry. Solid at the entry: a hit there (the outer cone where h = 1,
 * or an end face), unless the ray starts inside (then it looks for where it
 * leaves, as plain segments do). Otherwise the first sign change of g = w − h between
 * samples is bracketed and narrowed by bisection to a width of
 * 1e-9 · (h + r0 + r1 + D) in world units; the hit is the bracket's
 * midpoint. The inner cone's interval is computed analytically; its ends
 * are always samples (counted solid) and the ray jumps through it, so the
 * always-solid core is never stepped over. Solid up to the exit: a hit
 * there (h = 1 at the outer cone, or an end face).
 *   Step bound (derived, and what "exact" means here): consecutive samples
 * are at most `step` texels apart in s (u's difference taken the short way
 * round, times u_scale) and in t, and at most `step` apart in w (default
 * 1/8, at most 1/2). Each step is proposed from the previous one (doubled
 * when the last move was under half the bound) and halved until the bound
 * holds between the two samples' (s, t, w): the bound is measured, not
 * estimated from derivatives. The step alone could still step over a
 * graze (a ray dipping into a bump for less than a step), so every step
 * whose ends are on the same side is also proven free of crossings, or
 * split: along the ray w is convex (|q(t)| is the norm of an affine map,
 * r(y(t)) is affine), so its minimum over the step is at the clamped
 * stationary point of |q(t)| − r(y(t)) (closed form) and its maximum at an
 * end; h on the step's path is at most the ends' mean plus G · P/2 (and at
 * least the mean minus that), P the path's texel-space (L1) length, taken
 * as twice the ends' distance ℓ (a margin for the path's curvature), G the
 * largest difference of adjacent texels among the 4 × 4 texels around the
 * step (the bilinear interpolant's Lipschitz constant there; the step
 * keeps the path inside them). When min w − (mean h + G ℓ) > 0 (or, inside
 * the solid, max w − (mean h − G ℓ) ≤ 0) the step has no crossing;
 * otherwise it is halved and both halves are searched, left first. So a
 * crossing is missed only where the ray is in the solid (or out of it) for
 * less than the bisection width — the width the hit itself is found to.
 * The step has a floor of 1e-7 · (h + r0 + r1 + D) in world units (texels
 * smaller than that only exist that close to a pointed tip's axis), and at
 * most 2²⁰ samples are taken per segment and ray; reaching that limit
 * gives up on the segment (no hit from it) and reports hit.steps =
 * UINT32_MAX. hit.steps counts the samples (bisection included), a cost
 * measure for benchmarks; the relief calls set it on a miss too.
 *   Relief normals: `normal` is the true normal of the relief surface,
 * normalize(∇g) with ∇w = (q̂ − k a)/D, ∇u = (a × q̂)/(2π|q|) + (twist/2π) ∇v,
 * ∇v by central differences (δ = 1e-6 · segment size), and ∂h/∂s, ∂h/∂t
 * the exact derivatives of the bilinear interpolant (one-sided within the
 * cell that holds (s, t)). `shading_normal` is FORMAT.md's relief shading
 * normal: normalize(N − D (∂h/∂s · u_scale · (T_u / L_u + twist/2π · T_v /
 * L_v) + ∂h/∂t · v_scale · T_v / L_v)), N the eq. 8 normal above,
 * T_u = a × q̂, T_v = normalize(P1 − P0), L_u = 2π|q|, L_v = |P1 − P0| (on
 * a cylinder cut perpendicularly, twisted or not, it equals `normal`:
 * there ∇v = T_v / L_v).
 *
 * Images (meso_ref_frusta_render) follow shell_reference.h's conventions
 * exactly — the same rays per pixel (row 0 at the bottom, centre at
 * ndc ((2x+1)/W − 1, (2y+1)/H − 1), from the near to the far plane), the
 * same window depth, light, albedo and background — with the shading
 * colour = albedo · (0.25 + 0.75 w) · (0.15 + 0.85 max(0, n·l)), where n is
 * the hit's shading_normal turned to face the ray and w is the relief
 * height at the hit clamped to [0, 1] on a relief segment, and 1 on
 * everything else (plain segments, caps of plain segments, balls).
 *
 * Colour (FORMAT.md §7.2 kind 4, COLR): with a colour map, the albedo of a
 * segment hit (lateral, relief or cap) is the map at the hit's relief
 * coordinates (s, t) (meso_ref_frustum_relief_coords: u, v of the cone
 * through the hit), each texel decoded from sRGB to linear exactly, then
 * bilinear between texel centres ((i + ½)/W, (j + ½)/H), wrapping in s and
 * t; a ball's albedo is the map's mean linear colour. Without a map, the
 * view's albedo.
 */
#ifndef MESO_FRUSTUM_REFERENCE_H
#define MESO_FRUSTUM_REFERENCE_H

#include <stdint.h>

#include "frusta_pose.h"
#include "meso_file.h"
#include "shell_map.h"
#include "shell_reference.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct meso_ref_frustum {
    double c0[3], c1[3];   /* axis end points (c0 != c1) */
    double r0, r1;         /* radius at c0 and c1, >= 0 */
    double plane_n[2][3];  /* outward unit normals of the planes at the c0 and c1 ends */
    double plane_d[2];     /* plane i: plane_n[i]·p = plane_d[i] */
    int cap[2];            /* 1: the end is closed by a flat cap */
    double frame_x[3];     /* u = 0 direction, unit, perpendicular to the axis */
    double u_offset;       /* subtracted from u (§2.3 alignment), in turns */
    double twist;          /* radians of twist from v = 0 to v = 1 (§2.3) */
    /* Relief (§3); all zero (the default): none. */
    double u_scale;        /* relief s per turn of u (FSEG u_scale) */
    double v_offset;       /* relief t at v = 0 */
    double v_scale;        /* relief t per unit of v */
    double relief_depth;   /* D, world units; 0: no relief */
} meso_ref_frustum;

typedef struct meso_ref_ball {
    double center[3];
    double radius;
} meso_ref_ball;

typedef enum meso_ref_frustum_part {
    MESO_REF_PART_LATERAL = 0,
    MESO_REF_PART_CAP0,
    MESO_REF_PART_CAP1,
    MESO_REF_PART_BALL,
    MESO_REF_PART_COUNT
} meso_ref_frustum_part;

typedef struct meso_ref_frustum_hit {
    double t;                /* ray parameter: p = o + t d */
    double p[3];             /* the hit point */
    double normal[3];        /* true outward unit normal */
    double shading_normal[3];/* §2.4 interpolated normal (lateral); = normal elsewhere */
    double u, v;             /* §2.3; balls: 0, 0 */
    int32_t index;           /* segment (or ball) index in the model call, 0 for single calls */
    meso_ref_frustum_part part;
    /* Relief calls only (0 elsewhere): */
    int relief;              /* 1: the segment hit has relief (depth > 0 and a height field) */
    double w;                /* relief height coordinate of the hit, (|q| − r(y))/D */
    double tex[2];           /* relief texture coordinates (s, t) of the hit */
    uint32_t steps;          /* samples taken along this ray (all segments tried); UINT32_MAX: a cap was hit */
} meso_ref_frustum_hit;

/* The relief height field and the search's step bound (see above). */
typedef struct meso_ref_relief {
    meso_ref_texfn height; /* kind 1, W × H values in [0, 1]; kind 0 (or NULL relief): no relief */
    double step;           /* largest sample spacing, in texels (s, t) and in w; 0: 1/8 */
} meso_ref_relief;

/* Nearest intersection of the ray o + t d (d need not be unit) with the
 * segment's surface for t in [tmin, tmax]. Returns 1 and fills `hit`, or 0.
 * Entering and leaving hits are both surface hits: a ray starting inside
 * returns where it leaves. */
int meso_ref_frustum_intersect(const meso_ref_frustum* f, const double o[3], const double d[3], double tmin, double tmax,
    meso_ref_frustum_hit* hit);

/* 1 when p is inside the segment's solid (cone, both planes, right nappe). */
int meso_ref_frustum_contains(const meso_ref_frustum* f, const double p[3]);

/* (u, v) and the shading normal at a point p on (or near) the lateral
 * surface, as defined above. */
void meso_ref_frustum_uv(const meso_ref_frustum* f, const double p[3], double* u, double* v, double shading_normal[3]);

/* Nearest hit over a model: every segment and every ball (a plain loop with
 * a bounding-sphere rejection per segment). Returns 1 and fills `hit`
 * (index = segment or ball index; part says which), or 0. Relief fields
 * are ignored (the plain cones). */
int meso_ref_frusta_intersect(const meso_ref_frustum* segs, uint32_t seg_count, const meso_ref_ball* balls,
    uint32_t ball_count, const double o[3], const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit);

/* >>relief */

/* Nearest hit of the ray with one segment's relief solid (above), for t in
 * [tmin, tmax]. A segment with relief_depth 0, or `relief` NULL or kind 0,
 * is intersected exactly as meso_ref_frustum_intersect does. Returns 1 and
 * fills `hit` (relief, w, tex, steps too), or 0. */
int meso_ref_frustum_intersect_relief(const meso_ref_frustum* f, const meso_ref_relief* relief, const double o[3],
    const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit);

/* meso_ref_frusta_intersect with relief: nearest over every segment's
 * relief solid and every ball (bounding spheres of the outer cones). */
int meso_ref_frusta_intersect_relief(const meso_ref_frustum* segs, uint32_t seg_count, const meso_ref_ball* balls,
    uint32_t ball_count, const meso_ref_relief* relief, const double o[3], const double d[3], double tmin,
    double tmax, meso_ref_frustum_hit* hit);

/* Relief coordinates of any point p (inside the shell or not): (s, t) and
 * w as defined above (u, v of the cone through p). NULL outputs are
 * skipped; w is 0 when relief_depth is 0. */
void meso_ref_frustum_relief_coords(const meso_ref_frustum* f, const double p[3], double* s, double* t, double* w);

/* h(s, t) of a kind-1 height field (meso_ref_texfn_value) and the exact
 * derivatives of the bilinear interpolant, ∂h/∂s and ∂h/∂t (one-sided
 * within the cell holding (s, t); NULL outputs are skipped). */
double meso_ref_relief_height(const meso_ref_texfn* height, double s, double t, double* dhds, double* dhdt);

/* >>records and files */

/* FORMAT.md records (formats/frusta_pose.h) → reference segments and
 * balls: geometry from FRUS (plane e through center e: d = n·center),
 * caps, frame and relief parametrisation from FSEG. */
void meso_ref_frustum_from_rec(const meso_frustum_rec* rec, meso_ref_frustum* out);
void meso_ref_ball_from_rec(const meso_frustum_ball_rec* rec, meso_ref_ball* out);

/* A frusta object (kind 4) read from a file. */
typedef struct meso_ref_frusta {
    uint32_t seg_count, ball_count;
    meso_ref_frustum* segs;     /* seg_count, FRUS/FSEG order */
    meso_ref_ball* balls;       /* ball_count (NULL when 0) */
    meso_ref_relief relief;     /* height kind 1 from the object's RELF (the level's), kind 0 without one */
    float* relief_values;       /* owned storage of relief.height.values */
    uint32_t color_w, color_h;  /* the COLR colour map; 0 without one */
    double* color;              /* its texels decoded to linear RGB, 3 per texel, row 0 first (t = 0) */
    double ball_color[3];       /* its mean linear colour (balls) */
    float bbox_min[3], bbox_max[3]; /* the OBJT record's */
} meso_ref_frusta;

/* Loads object `object_id` (kind 4): FRUS + FSEG (required, equal counts),
 * BALL, RELF and COLR (optional; RELF must be U8 or U16 × 1, values / max;
 * COLR U8 × 4, W × H × 1) through meso_file_read_chunk. MESO_ERR_NOT_FOUND: no such object or a required
 * chunk is missing; MESO_ERR_CORRUPT: counts disagree; MESO_ERR_UNSUPPORTED:
 * a RELF dtype other than U8/U16 × 1, a COLR other than U8 × 4, W × H × 1. Free with meso_ref_frusta_free. */
meso_result meso_ref_frusta_load(meso_file* f, uint32_t object_id, meso_ref_frusta* out, meso_error* err);
/* The same for level `lod` of a levelled file (FORMAT.md §7.10: per chunk
 * type the smallest lod >= `lod`): a native coarser level's own relief map
 * (bake/height_field_levels.h). meso_ref_frusta_load is lod 0. */
meso_result meso_ref_frusta_load_level(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_frusta* out,
                                       meso_error* err);
void meso_ref_frusta_free(meso_ref_frusta* m);

/* The albedo of a hit of meso_ref_frusta_intersect_relief on `m` (its
 * index and part) with m's colour map, as above; returns 0 (and leaves
 * `albedo` alone) when m has no colour map. */
int meso_ref_frusta_albedo(const meso_ref_frusta* m, const meso_ref_frustum_hit* hit, double albedo[3]);

/* Renders a frusta object with the conventions above (shell_reference.h's
 * rays, depth, light and albedo; v->curved, uv_scale and samples_per_prism
 * are ignored; v->threads 0 = one thread per online core, on pthreads —
 * the image never depends on it). A bounding-volume hierarchy over the
 * segments' and balls' bounding spheres picks the candidates; the hit of a
 * pixel is meso_ref_frusta_intersect_relief's over the whole object, t in
 * [0, 1] (near to far plane). `out` is allocated here; free it with
 * meso_ref_image_free. MESO_ERR_INVALID_ARG: bad sizes or singular
 * matrices; MESO_ERR_OUT_OF_MEMORY. */
meso_result meso_ref_frusta_render(const meso_ref_frusta* m, const meso_ref_view* v, meso_ref_image* out);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FRUSTUM_REFERENCE_H */
