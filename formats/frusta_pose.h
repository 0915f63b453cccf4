/*
 * frusta_pose.h — a frusta object's records (FORMAT.md §7.2 kind 4, §7.5–
 * §7.7) and the pose rebuild of relief-mapped-conical-frusta.md §2.2–2.3:
 * from skeleton node positions to cones, cutting planes and u frames.
 *
 * Pure C11, no GL, no allocation. libmeso calls meso_frusta_pose every time
 * the host moves the skeleton (the paper's animation: "the splitting planes
 * between segments have to be recomputed in each time step"); mesobake
 * writes FRUS through the same call, so the rest pose a runtime rebuilds is
 * the baked one bit for bit.
 *
 * The rebuild, per frustum i with nodes P0 = node_pos[node0], P1 =
 * node_pos[node1], node radii R0, R1 (the cone: radius linear from R0 at P0
 * to R1 at P1):
 *  - an end of kind tip or ball: the plane ⟂ the axis through its node,
 *    normal pointing out of the frustum;
 *  - an end of kind joint: meso_frustum_joint_plane of the joint with
 *    `other` (segment 1 is the frustum whose c1 end is at the joint when
 *    exactly one is, else the lower index; the construction is symmetric
 *    in the two up to rounding), normal pointing out of each frustum;
 *  - centre e = where the axis meets plane e, radius e = the cone radius
 *    there (clamped at 0: a plane past the apex is a degenerate joint the
 *    baker turns into a ball);
 *  - frames (§2.3): align_from = −1 keeps its frame_x, turned with the axis
 *    by the minimal rotation from the axis of the previous pose (node
 *    positions carry no turn about a root frustum's own axis, so that turn
 *    is not followed: a host that twists a root rotates its frame_x); otherwise
 *    frame_x = align_from's frame_x projected ⟂ to the axis (any ⟂ vector
 *    when they are parallel) and, when this frustum's shared end is a joint,
 *    u_offset = the u of the point where align_from's u = 0 generator meets
 *    the joint plane (else 0). Records are processed in order, which is why
 *    align_from must be earlier.
 *  - balls: centre = the node's position.
 */
#ifndef MESO_FRUSTA_POSE_H
#define MESO_FRUSTA_POSE_H

#include <stdint.h>

#include "meso_layout.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One frustum: its FSEG record (topology, parametrisation) and its FRUS
 * record (geometry of the current pose). */
typedef struct meso_frustum_rec {
    /* FSEG */
    uint32_t node[2];
    float node_radius[2];
    int32_t other[2];
    uint32_t flags; /* MESO_FSEG_* */
    int32_t align_from;
    float frame_x[3];
    float u_offset, twist, u_scale, v_offset, v_scale, relief_depth;
    /* FRUS */
    float center[2][3];
    float radius[2];
    float plane[2][3]; /* outward unit normals; plane e passes through center[e] */
    uint32_t skel_node;
} meso_frustum_rec;

typedef struct meso_frustum_ball_rec {
    float center[3];
    float radius;
    uint32_t node;
} meso_frustum_ball_rec;

static inline uint32_t meso_frustum_rec_end_kind(const meso_frustum_rec* r, int end)
{
    return (r->flags >> (end ? MESO_FSEG_KIND1_SHIFT : MESO_FSEG_KIND0_SHIFT)) & 3u;
}

/* The geometry of a record's current pose in double precision: c0 =
 * center[0], unit axis a towards center[1], length h, radius slope k, the
 * u frame x = frame_x and z = x × a. */
typedef struct meso_frustum_frame {
    double c0[3], a[3], x[3], z[3];
    double h, k;
} meso_frustum_frame;

void meso_frustum_rec_frame(const meso_frustum_rec* r, meso_frustum_frame* f);

/* Unit radial direction at angle phi: sin(phi) x + cos(phi) z (§2.3: u = 0
 * at phi = 0 before offsets). */
void meso_frustum_frame_radial(const meso_frustum_frame* f, double phi, double w[3]);

/* Where the generator with radial direction w of the parallel cone
 * r(y) + delta meets plane e: fills p (may be NULL) and returns the axial
 * coordinate y from c0 (0 or h when the generator is parallel to the
 * plane). */
double meso_frustum_rec_cut(const meso_frustum_rec* r, const meso_frustum_frame* f, double delta, const double w[3],
    int e, double p[3]);

/* Little-endian record codecs (no validation: read chunks with
 * meso_file_read_chunk, which validates them). */
void meso_frustum_rec_decode(const uint8_t frus[MESO_FRUS_RECORD_SIZE], const uint8_t fseg[MESO_FSEG_RECORD_SIZE],
    meso_frustum_rec* out);
void meso_frustum_rec_encode(const meso_frustum_rec* in, uint8_t frus[MESO_FRUS_RECORD_SIZE],
    uint8_t fseg[MESO_FSEG_RECORD_SIZE]);
void meso_frustum_ball_decode(const uint8_t rec[MESO_BALL_RECORD_SIZE], meso_frustum_ball_rec* out);
void meso_frustum_ball_encode(const meso_frustum_ball_rec* in, uint8_t rec[MESO_BALL_RECORD_SIZE]);

/* The §2.2 cutting plane of a joint J between segment 1 (from O1, radius
 * rO1, to J1 with radius rJ1) and segment 2 (from J2, radius rJ2, to O2,
 * radius rO2); J1 and J2 are the joint's position as each segment sees it
 * (equal unless a zero-length segment was merged away). Fills the unit
 * normal n (oriented along M1 + M2, i.e. out of segment 1), d (plane:
 * n·p = d) and the points A, B (bake/frustum_model.h, "Joint plane"). */
void meso_frustum_joint_plane(const double O1[3], double rO1, const double J1[3], double rJ1, const double J2[3],
    double rJ2, const double O2[3], double rO2, double n[3], double* d, double A[3], double B[3]);

/* Rebuilds center, radius, plane, frame_x and u_offset of every record, and
 * every ball's centre, from node positions (3 floats per node). Returns 0,
 * or -1 when a node index is out of range, `other`/`align_from` is out of
 * range, or a frustum has zero length (records are then left partly
 * updated). Cost: measured in tests/bench (bench_frusta). */
int meso_frusta_pose(meso_frustum_rec* recs, uint32_t count, meso_frustum_ball_rec* balls, uint32_t ball_count,
    const float* node_pos, uint32_t node_count);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FRUSTA_POSE_H */
