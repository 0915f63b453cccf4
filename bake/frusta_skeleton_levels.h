/*
 * frusta_skeleton_levels.h — coarser skeletons of a frusta object, each
 * with a measured error (internal; FORMAT.md §7.10, issue 14: "Frusta:
 * relief-map mip levels and coarser skeletons"). frusta_skeleton_levels.c
 * says how the skeletons are chosen and how far their surfaces are from
 * level 0's.
 */
#ifndef MESO_FRUSTA_SKELETON_LEVELS_H
#define MESO_FRUSTA_SKELETON_LEVELS_H

#include <stdint.h>

#include "frusta_chunks.h"
#include "frustum_model.h"
#include "meso_bake.h"

/* At most this many coarser skeletons. */
#define MESOI_SKELETON_LEVELS_MAX 3

typedef struct mesoi_skeleton_level {
    /* The level's records and balls. Its SKEL is level 0's (skel, node_pos,
     * node_count: copies), and every node index (FSEG node0/node1, FRUS
     * skel_node, BALL node) is one of level 0's SKEL nodes, so a host that
     * poses level 0's skeleton poses this level with the same call. */
    meso_frusta_object obj;
    double distance;  /* max over relief coordinates (s, t) and heights of |p_level − p_0|, object units */
    uint32_t nodes;   /* skeleton nodes its frusta use */
} mesoi_skeleton_level;

typedef struct mesoi_skeleton_levels_input {
    const meso_skeleton* sk;           /* the input skeleton level 0 was built from */
    const meso_frustum_options* fo;    /* the options it was built with */
    const meso_frusta_relief_params* rp;
    const meso_frusta_object* fine;    /* level 0 */
    double h_lo, h_hi;                 /* the relief heights the levels draw lie in [h_lo, h_hi] (0, 0: none) */
    int free_u;                        /* 1: nothing is drawn by u (no relief, no colour map), so u may turn */
    uint32_t max_levels;               /* <= MESOI_SKELETON_LEVELS_MAX */
    double limit;                      /* a level whose distance reaches this is not kept, nor any after it */
} mesoi_skeleton_levels_input;

/* The coarser skeletons, finest first: *levels gets *count entries (free
 * with mesoi_skeleton_levels_free). Where none or fewer than max_levels
 * were kept, *why says why (a static string; else NULL). */
meso_result mesoi_skeleton_levels_build(const mesoi_skeleton_levels_input* in, mesoi_skeleton_level** levels,
                                        uint32_t* count, const char** why, meso_error* err);

void mesoi_skeleton_levels_free(mesoi_skeleton_level* levels, uint32_t count);

/* The distance (above) of `coarse` from `fine`, both over level 0's SKEL:
 * each of coarse's frusta spans a chain of fine's (the same end nodes)
 * and carries its relief coordinates. Returns -1 when a coarse frustum
 * spans no chain of fine's or their balls differ (not comparable). */
double mesoi_skeleton_level_distance(const meso_frusta_object* fine, const meso_frusta_object* coarse, double h_lo,
                                     double h_hi, int free_u);

#endif /* MESO_FRUSTA_SKELETON_LEVELS_H */
