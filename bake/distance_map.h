/*
 * distance_map.h — conservative distance maps (DIST chunks, FORMAT.md §7.2)
 * of a shell's texture function, for sphere tracing.
 *
 * Cell (i, j, k) of a W × H × D map covers [i/W, (i+1)/W] × [j/H, (j+1)/H] ×
 * [k/D, (k+1)/D] of one tile of texture space (s, t, w); its value is a lower
 * bound on the distance from any point of the cell to the solid of the
 * FILTERED function (bilinear heights / trilinear densities, exactly as the
 * runtime samples them), the solid repeating with period 1 in s and t and
 * absent below w = 0 and above w = 1. Distances are Euclidean in texture
 * space: one tile = 1 along s and t, the shell = 1 along w.
 *
 * How (all exact up to a 1e-6 margin for the runtime's float arithmetic):
 *  1. Mark the cells that may touch the solid. The filtered function is
 *     multilinear between texel centres, so its maximum over a cell is its
 *     maximum over the grid of cell faces and texel-centre planes inside the
 *     cell. A height-field cell may touch the solid iff k/D <= that maximum
 *     over the cell's footprint; a density cell iff its maximum is >= 1/2.
 *  2. Dilate the marks by one cell along each axis (3 × 3 × 3 box; wraps in
 *     s and t). For integer offsets, min over e in {-1, 0, 1} of |Δ − e| is
 *     max(0, |Δ| − 1), the gap between two cells, so the distance from a
 *     cell's centre to the nearest dilated mark is the exact box-to-box
 *     distance to the nearest marked cell — a lower bound on the distance
 *     from any point of the cell to any solid inside a marked cell.
 *  3. Exact Euclidean distance transform of the dilated marks with cell sizes
 *     (1/W, 1/H, 1/D): separable lower envelopes of parabolas (P. Felzenszwalb,
 *     D. Huttenlocher, "Distance Transforms of Sampled Functions", Theory of
 *     Computing 8, 2012), periodic in s and t by running each line over three
 *     copies of the period and keeping the middle one (the nearest copy of any
 *     point is within half a period).
 * Lines are independent and run on OpenMP threads; the result does not
 * depend on the thread count.
 *
 * Store types: U8 (the default: 1 byte per cell, distances capped at 1 and
 * quantised down to multiples of 1/255), U16 (multiples of 1/65535) or F32
 * (rounded down to a float; cells of a function without any solid hold
 * 1e30). Quantisation always rounds down, so stored values stay lower bounds.
 */
#ifndef MESO_DISTANCE_MAP_H
#define MESO_DISTANCE_MAP_H

#include "texture_function.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest distance-map side accepted (mesobake --dist-res). */
#define MESO_DISTMAP_MAX_RES MESO_BAKE_MAX_DIST_RES /* 512 (meso_bake.h) */

typedef struct meso_distmap {
    uint32_t dims[3];     /* W, H, D */
    float* dist;          /* W*H*D lower bounds, s fastest; INFINITY when the function has no solid */
    uint16_t dtype;       /* MESO_DTYPE_U8, _U16 or _F32 */
    void* encoded;        /* the DIST payload (little-endian) */
    size_t encoded_size;  /* bytes */
    uint64_t solid_cells; /* cells that may touch the solid (before dilation) */
} meso_distmap;

/* Build the distance map of `f` at `dims` (each 1..MESO_DISTMAP_MAX_RES),
 * stored as `dtype`. threads <= 0: all cores. Free with meso_distmap_free. */
meso_result meso_distmap_build(const meso_texfn* f, const uint32_t dims[3], uint16_t dtype, int threads,
                               meso_distmap* out, meso_error* err);
void meso_distmap_free(meso_distmap* m);

/* The stored value of cell `i` as the runtime reads it (value / max, or the
 * float), in texture-space units. */
double meso_distmap_stored(const meso_distmap* m, size_t i);

/* The default resolution for `f` (mesobake --dist-res):
 *  - W, H: half the texture's W, H, clamped to [8, 128];
 *  - D of a volume: half its depth, clamped to [8, 128];
 *  - D of a height field: 1 / step rounded up to a multiple of 8 and clamped
 *    to [8, 128], where step is the first quartile of the non-negligible
 *    (>= 1/256) height differences between neighbouring columns of the
 *    W × H footprints (each column's maximum height): cells are about as
 *    tall as the finer of the height steps between neighbouring columns, so
 *    a ray crossing a slope advances about a cell per step. A flat field
 *    gets 8. */
void meso_distmap_default_res(const meso_texfn* f, uint32_t dims[3]);

/* Step 1 above: the maximum of the filtered function over each cell, into
 * out[W*H] for a height field (footprints; dims[2] ignored) or out[W*H*D]
 * for a volume. threads <= 0: all cores. */
meso_result meso_distmap_cell_max(const meso_texfn* f, const uint32_t dims[3], int threads, float* out,
                                  meso_error* err);

/* Step 3 above, exposed for tests: sqdist[c] = squared Euclidean distance
 * from the centre of cell c to the centre of the nearest cell with mask != 0,
 * with cell sizes `spacing` and axis a periodic when periodic[a] (INFINITY
 * when no cell is marked). */
meso_result meso_distmap_edt(const uint8_t* mask, const uint32_t dims[3], const double spacing[3],
                             const int periodic[3], double* sqdist, int threads, meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_DISTANCE_MAP_H */
