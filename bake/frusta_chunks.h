/*
 * frusta_chunks.h — a frustum model (frustum_model.h) as the records of a
 * frusta object (FORMAT.md §7.2 kind 4, §7.4–7.7): SKEL in topological
 * order, FRUS + FSEG in breadth-first order (so every align_from is
 * earlier), BALL, and the relief parametrisation.
 *
 * Decisions:
 *  - FRUS geometry is written by meso_frusta_pose (formats/frusta_pose.c)
 *    from the float node positions, so a runtime's rest-pose rebuild gives
 *    the same bytes.
 *  - Relief texture coordinates: u_scale = `u_repeat` (tiles around the
 *    axis); v_scale = u_repeat · h / (2π r̄), h the segment's length and r̄
 *    the mean of its node radii plus half the relief depth, so a texel is
 *    about square on the surface; v_offset continues t across joints and
 *    ball joints along the breadth-first tree (t at the shared node is the
 *    same on both sides), reduced modulo 1 (the map wraps).
 *  - The bounding box covers, per frustum, both elliptical cuts of the
 *    outer cone (r + depth) sampled at 256 generators, padded by the
 *    largest chord sagitta of that sampling, and the balls.
 */
#ifndef MESO_FRUSTA_CHUNKS_H
#define MESO_FRUSTA_CHUNKS_H

#include <stdint.h>

#include "frusta_pose.h"
#include "frustum_model.h"
#include "meso_file.h"
#include "skeleton_swc.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct meso_frusta_relief_params {
    double depth;    /* world units; 0: no relief */
    double u_repeat; /* relief tiles around the circumference; <= 0: 1 */
} meso_frusta_relief_params;

/* The records of a frusta object, ready to encode. Owned arrays: free with
 * meso_frusta_object_free. */
typedef struct meso_frusta_object {
    uint32_t count, ball_count, node_count;
    meso_frustum_rec* recs;
    meso_frustum_ball_rec* balls;
    uint8_t* skel;             /* node_count SKEL records (32 bytes each) */
    float* node_pos;           /* 3 per node, SKEL order */
    uint32_t* skel_of_input;   /* input node index -> SKEL index */
    float bbox_min[3], bbox_max[3];
} meso_frusta_object;

meso_result meso_frusta_object_build(const meso_skeleton* sk, const meso_frustum_model* m,
    const meso_frusta_relief_params* relief, meso_frusta_object* out, meso_error* err);

/* FRUS, FSEG and BALL payloads (malloc'd; the caller frees them). */
meso_result meso_frusta_object_encode(const meso_frusta_object* o, uint8_t** frus, uint8_t** fseg, uint8_t** ball,
    meso_error* err);

void meso_frusta_object_free(meso_frusta_object* o);

#ifdef __cplusplus
}
#endif
#endif /* MESO_FRUSTA_CHUNKS_H */
