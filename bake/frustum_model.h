/*
 * frustum_model.h — a skeleton skinned with conical frusta
 * (relief-mapped-conical-frusta.md §2): one cone frustum per parent→child
 * segment, one cutting plane per joint, the §2.3 u alignment, and what the
 * paper leaves open (branches, caps that intersect at sharp joints).
 *
 * Decisions where §2 is vague or garbled (numbers: tests/frusta):
 *  - Cone (eq. 1, 2): radius linear along the axis, r(y) = r0 + (r1 − r0) y/h,
 *    the paper's cone without its apex height h' (which is infinite for a
 *    cylinder). Radii are the SWC node radii at the two ends, so a zero
 *    radius makes a pointed tip.
 *  - Joint plane (eq. 3–5): a joint is a node where exactly two segments
 *    meet. With O1 the far end of the first segment, J the joint, O2 the far
 *    end of the second, M1 = unit(J − O1), M2 = unit(O2 − J),
 *    Nm = unit(M1 × M2) (when |M1 × M2| < 1e-9, Nm = a unit vector ⟂ M1),
 *    p_i = M_i × Nm. In the medial plane the boundary lines of the two cones
 *    on side s (s = −1 gives A, as eq. 4's L1 = C1 − r1 (M1 × Nm);
 *    s = +1 gives B) are L1 L2 = (O1 + s rO1 p1, J + s rJ1 p1) and
 *    L3 L4 = (J + s rJ2 p2, O2 + s rO2 p2); A and B are the intersections
 *    of these line pairs, solved in 2-D in the medial plane. When the two
 *    lines are parallel (|sin| < 1e-9: e.g. a straight chain of equal slope)
 *    the point is the midpoint of L2 and L3. Nc = unit((A − B) × Nm) oriented
 *    with Nc·(M1 + M2) > 0, through A. If |A − B| is ~0 (zero radius at the
 *    joint) the plane is the bisector: Nc = unit(M1 + M2) through J.
 *    What this guarantees: A and B lie on both cones, so the two elliptical
 *    cut curves share the major axis AB; the minor axes agree only in
 *    special cases (equal radii: a mitred pipe, exact), otherwise there is a
 *    seam gap (§2.2 says so) until the minor-axis fit below closes it.
 *    `joints[i].seam_gap` measures it: the largest distance, within the
 *    plane, between a point on one cut curve and the point of the other
 *    curve at the same angle around that other cone's axis, both ways.
 *  - Tips (a node with one segment): the plane perpendicular to the axis at
 *    the node, closed by a flat cap when the radius is > 0 (the paper does
 *    not say; a closed surface needs it).
 *  - Branch points (three or more segments at a node) — open in the paper.
 *    Rule here: every segment at the node is cut by the plane perpendicular
 *    to its own axis through the node, no caps, and a ball (sphere) of the
 *    largest of their radii at the node is added. Each end disc lies inside
 *    the ball, so the union has no hole or crack; where a cone narrows away
 *    from the node the ball bulges out of it (a visible knob, not a hole).
 *  - Cap intersections (open in the paper): a segment's cut is valid when
 *    every generator line of its cone crosses plane 0 going in and plane 1
 *    going out, on the right nappe (r ≥ 0), with y0(φ) < y1(φ) — checked
 *    exactly for the orientation and nappe (extremes at two generators) and
 *    at 512 generators for y0 < y1. A segment that fails is a cap
 *    intersection (`cap_intersections_found`, counted over segments in the
 *    paper's construction). Handling: each joint at an end of a failing
 *    segment becomes a ball joint (the branch rule above), then the check
 *    repeats until nothing changes; segments still failing are
 *    `cap_intersections_unhandled` (perpendicular planes at both ends never
 *    cross, so this stays 0).
 *  - Zero-length segments (neurom_fat_end.swc repeats a point) are dropped;
 *    their two nodes count as one for joints and branches.
 *  - u (§2.3): segments are visited breadth-first over joints. The first
 *    segment of a component gets frame_x = unit(a × e), e the world axis
 *    least aligned with its axis a, and u_offset 0. Across a joint the next
 *    segment's frame_x is the previous one projected ⟂ to its axis, and its
 *    u_offset is the paper's u_t: the u, in the new frame, of the point
 *    where the previous segment's u = 0 generator meets the joint plane.
 *    Across a ball joint the frame is projected the same way and
 *    u_offset = 0: u is not matched across a ball (align_across stops).
 *    twist turns the u = 0 generator by `twist` radians from v = 0 to
 *    v = 1 (formats/FORMAT.md, frusta: u = atan2(q·x, q·z)/2π − u_offset +
 *    v·twist/2π); the alignment above takes it into account on both sides
 *    of a joint, so a twisted segment still meets its neighbour's u at the
 *    aligned point. Elsewhere on the seam u matches only where the two
 *    segments' angles about their axes differ by a constant (straight
 *    chains; a mitred bend whose frame_x is normal to the bend's plane);
 *    elsewhere the one-point alignment leaves a jump, up to ~2e-2 turns on
 *    the tapered chain and the saguaro of tests/frusta/test_frusta_twist.c. On a joint plane v is
 *    exactly 1 (or 0) on the whole cut, so twist only adds constants
 *    there: it moves the aligned point, which shifts that jump by one
 *    constant per joint, and never changes its spread.
 *  - Twist (§2.3's "adding vθ to the u coordinate", θ per segment; the
 *    paper gives no way to choose θ). Each segment's twist is its child
 *    node's `twist_deg` when the skeleton gives one (the .skel `twist=`
 *    field), else `twist_per_length` times the segment's length |child −
 *    parent| (the length v_scale uses, frusta_chunks.h), so a rate makes
 *    the texture turn uniformly along the skeleton whatever its
 *    segmentation (uniform in v; with an oblique cut, v is not exactly
 *    proportional to length along every generator). Sign: positive twist
 *    turns the texture by −θ about the axis a from v = 0 to 1 (u = const
 *    is φ = const − vθ, φ the right-handed angle about a), so a line of
 *    constant u is a left-handed helix; with the same rate everywhere
 *    every segment's helix has the same handedness, whichever way its axis
 *    points. Without either, twist = 0 (the paper's untwisted frusta).
 *  - Minor-axis fit (§2.2): at each joint the radius of segment 2 (the one
 *    leaving the joint) at the joint is adjusted until the minor semi-axes
 *    of the two cut ellipses agree (bisection on [r/4, 4r] around the node
 *    radius, the bracket nearest the node radius); the plane is recomputed
 *    with it. Then the two ellipses share centre, major axis AB and minor
 *    axis, so they are the same curve and the seam closes (seam_gap → 0,
 *    tests/frusta). Segment 2's far radius is kept, so the shape changes
 *    only near the joint; radius_change_max reports how far it moved. All
 *    joints are swept until no radius moves (planes depend on neighbours'
 *    radii). Where no radius within a factor 1.25 of the node's closes the
 *    seam (short, fat segments: neurons), or where the seam gap measured
 *    after the fit is still above 1e-6 of the joint radius, the joint
 *    becomes a ball joint (`unfitted_joints`): a knob, never a crack.
 *    The seam gap below is measured after the fit.
 * What remains: u matched along the whole seam (not only at one point), u
 * running in opposite senses across
 * a joint where both segments point away from it (a root with two children),
 * §2.4 normals across ball joints, bounding pyramids (§2.6).
 */
#ifndef MESO_FRUSTUM_MODEL_H
#define MESO_FRUSTUM_MODEL_H

#include <stdint.h>

#include "meso_file.h"
#include "skeleton_swc.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum meso_frustum_end_kind {
    MESO_FRUSTUM_END_TIP = 0, /* one segment at the node: perpendicular plane, flat cap if r > 0 */
    MESO_FRUSTUM_END_JOINT,   /* two segments: the §2.2 cutting plane, shared */
    MESO_FRUSTUM_END_BALL,    /* branch point, or a joint turned into a ball joint */
    MESO_FRUSTUM_END_KIND_COUNT
} meso_frustum_end_kind;

typedef struct meso_frustum_segment {
    uint32_t node[2];         /* skeleton node at the c0 (parent) and c1 (child) end */
    double c0[3], c1[3];      /* axis end points */
    double r0, r1;            /* radii at c0, c1 */
    double plane_n[2][3];     /* outward unit normals of the planes at the c0 / c1 end */
    double plane_d[2];        /* plane i: plane_n[i]·p = plane_d[i] */
    int cap[2];               /* 1: flat cap closes that end */
    meso_frustum_end_kind end_kind[2];
    int32_t joint[2];         /* index into joints[] at each end, or -1 */
    int32_t ball[2];          /* index into balls[] at each end, or -1 */
    double frame_x[3];        /* u = 0 direction (unit, ⟂ axis) */
    double u_offset;          /* turns, subtracted from u */
    double twist;             /* radians over v in [0, 1] (see "Twist" above) */
    double cut_margin;        /* min over generators of (y1 − y0) in world units; <= 0: caps cross */
    int32_t align_from;       /* segment whose frame this one's is carried from (breadth-first), or -1 */
    int align_end;            /* end of this segment at the node shared with align_from */
    int align_from_end;       /* end of align_from there */
} meso_frustum_segment;

typedef struct meso_frustum_joint {
    uint32_t node;            /* skeleton node (the representative of merged zero-length nodes) */
    uint32_t segment[2];      /* the two segments */
    int end[2];               /* which end (0: c0, 1: c1) of each is at the joint */
    double a[3], b[3];        /* the points A and B of §2.2 */
    double plane_n[3];        /* Nc, oriented along M1 + M2 */
    double plane_d;
    double seam_gap;          /* see the header comment (world units) */
    int ball;                 /* 1: turned into a ball joint (cap intersection handling) */
} meso_frustum_joint;

typedef struct meso_frustum_ball {
    uint32_t node;
    double center[3];
    double radius;
} meso_frustum_ball;

typedef struct meso_frustum_options {
    int keep_cap_intersections; /* 1: report them but keep the paper's planes (default 0: ball joints) */
    int no_minor_axis_fit;      /* 1: skip the §2.2 minor-axis fit (default 0: fit) */
    double max_joint_angle_deg; /* joints bending more than this become ball joints; <= 0: no limit */
    double twist_per_length;    /* radians of twist per unit of segment length (default 0); a node's
                                   twist_deg replaces it for the segment ending there */
    const uint8_t* ball_nodes;  /* NULL, or per skeleton node: 1 makes a joint there a ball joint (a coarser
                                   skeleton keeps level 0's balls: frusta_skeleton_levels.c) */
} meso_frustum_options;

typedef struct meso_frustum_stats {
    uint32_t segments;
    uint32_t joints;                      /* nodes where exactly two segments meet */
    uint32_t branch_points;               /* nodes where three or more meet */
    uint32_t tips;                        /* nodes with one segment */
    uint32_t degenerate_segments;         /* zero-length, dropped */
    uint32_t cap_intersections_found;     /* segments whose caps cross with the paper's planes */
    uint32_t cap_intersections_unhandled; /* ... still crossing after the handling */
    uint32_t ball_joints;                 /* joints turned into balls by the handling */
    double seam_gap_max;                  /* over §2.2 joints (not ball joints), world units */
    double seam_gap_mean;
    double radius_change_max;             /* largest radius the §2.2 fit moved away from its node's */
    double radius_change_mean;            /* mean over segment ends */
    uint32_t unfitted_joints;             /* joints the §2.2 fit could not close: made ball joints */
    uint32_t sharp_joints;                /* joints over max_joint_angle_deg: made ball joints */
} meso_frustum_stats;

/* The frustum model. Arrays are malloc'd and owned: free with
 * meso_frustum_model_free. */
typedef struct meso_frustum_model {
    uint32_t segment_count, joint_count, ball_count;
    meso_frustum_segment* segments; /* in skeleton child-node order */
    meso_frustum_joint* joints;
    meso_frustum_ball* balls;
    uint32_t* order;                /* segments in breadth-first order: align_from comes before */
    meso_frustum_stats stats;
} meso_frustum_model;

/* Builds the model of a skeleton. `opt` may be NULL (defaults). Fails only
 * on NULL arguments (MESO_ERR_INVALID_ARG), a skeleton with no segment of
 * non-zero length (MESO_ERR_CORRUPT, issue 3149: an input that cannot be
 * drawn), MESO_ERR_OUT_OF_MEMORY. */
meso_result meso_frustum_model_build(const meso_skeleton* s, const meso_frustum_options* opt, meso_frustum_model* out,
    meso_error* err);

void meso_frustum_model_free(meso_frustum_model* m);

/* Lateral area of a segment between its two planes (caps excluded),
 * integrated over `samples` generators (0: 1024) with the axial integral in
 * closed form. For perpendicular planes it equals π (r0 + r1) · slant. */
double meso_frustum_lateral_area(const meso_frustum_segment* s, uint32_t samples);

/* y (axial coordinate from c0) where the generator of segment s with unit
 * radial direction w meets the plane at end e; 0 when parallel. */
int meso_frustum_generator_plane(const meso_frustum_segment* s, int e, const double w[3], double* y);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FRUSTUM_MODEL_H */
