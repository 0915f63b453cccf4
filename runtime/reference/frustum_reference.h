/*
 * frustum_reference.h — the exact CPU reference for relief-mapped conical
 * frusta (relief-mapped-conical-frusta.md §2): analytic ray–cone
 * intersection clipped by the segment's two cutting planes (§2.5), the
 * (u, v) parametrisation (§2.3), the cone's normal and the paper's
 * interpolated shading normal (§2.4). Double precision, no relief yet.
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
 * (the paper's u = atan(x/z)/2π with its quadrant made explicit); v is the
 * ratio (7) along the cone generator through p between its intersections
 * P0, P1 with the two planes; on the generator the distance ratio equals the
 * ratio of axial coordinates, v = (y − y0)/(y1 − y0).
 * Normals: `normal` is the cone's (or cap's, or ball's) true outward unit
 * normal; `shading_normal` is eq. 8: normalize((1 − v) N_l + v N_u) with
 * N_l = normalize(P0 − c0), N_u = normalize(P1 − c1) (caps and balls: the
 * true normal).
 */
#ifndef MESO_FRUSTUM_REFERENCE_H
#define MESO_FRUSTUM_REFERENCE_H

#include <stdint.h>

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
} meso_ref_frustum_hit;

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
 * (index = segment or ball index; part says which), or 0. */
int meso_ref_frusta_intersect(const meso_ref_frustum* segs, uint32_t seg_count, const meso_ref_ball* balls,
    uint32_t ball_count, const double o[3], const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FRUSTUM_REFERENCE_H */
