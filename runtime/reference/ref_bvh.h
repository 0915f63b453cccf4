/*
 * ref_bvh.h — the one bounding-volume hierarchy of the CPU references
 * (internal): axis-aligned boxes of items (shell prisms, frusta segments and
 * balls), median split along the longest axis of the box centres, leaves of
 * at most four items; rays visit the nearer child first and stop at the
 * nearest hit found so far. Built once per render, read-only while the rows
 * are traced on many threads.
 */
#ifndef MESO_REF_BVH_H
#define MESO_REF_BVH_H

#include <stdint.h>

#include "meso_file.h"

typedef struct mesoi_ref_bvh_node {
    double lo[3], hi[3];
    uint32_t first, count; /* leaf: items[first .. first + count); inner: count 0, children first, first + 1 */
} mesoi_ref_bvh_node;

typedef struct mesoi_ref_bvh {
    mesoi_ref_bvh_node* nodes; /* node 0 is the root; NULL when there are no items */
    uint32_t node_count;
    uint32_t* items; /* the item indices, grouped by leaf */
    uint32_t item_count;
} mesoi_ref_bvh;

/* Builds the hierarchy over `n` items: items[i] (an index into `box`), each
 * with box[items[i]] = {lo x, y, z, hi x, y, z}. Ties in the split order
 * are broken by item index, so the tree depends only on the boxes.
 * MESO_ERR_OUT_OF_MEMORY leaves *b empty. */
meso_result mesoi_ref_bvh_build(mesoi_ref_bvh* b, const double (*box)[6], const uint32_t* items, uint32_t n);
void mesoi_ref_bvh_free(mesoi_ref_bvh* b);

/* Clips [*t0, *t1] of the ray o + t·d (inv = 1/d per axis, any value where
 * d is 0) to the box; 0 when nothing is left (then *t0, *t1 untouched). */
int mesoi_ref_box_interval(const double lo[3], const double hi[3], const double o[3], const double d[3],
    const double inv[3], double* t0, double* t1);

/* Calls leaf(user, items, count, tmax) for every leaf whose box the ray
 * o + t·d crosses for t in [0, *tmax], nearer child first; the callback
 * lowers *tmax when it finds a nearer hit, which prunes what follows. */
typedef void (*mesoi_ref_bvh_leaf_fn)(const void* user, const uint32_t* items, uint32_t count, double* tmax);
void mesoi_ref_bvh_trace(const mesoi_ref_bvh* b, const double o[3], const double d[3], const double inv[3],
    double* tmax, mesoi_ref_bvh_leaf_fn leaf, const void* user);

#endif /* MESO_REF_BVH_H */
