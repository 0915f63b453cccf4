/*
 * height_field_levels.h — native coarser levels of an object drawn from a
 * height field (FORMAT.md §7.10; issue 14): a shell's texture function
 * (with a distance map per level) or a frusta object's relief map. The
 * height field is halved level by level (a prefiltered pyramid), and how
 * far each level's heights are from level 0's is measured exactly
 * (internal, mesoi_ prefix).
 */
#ifndef MESO_HEIGHT_FIELD_LEVELS_H
#define MESO_HEIGHT_FIELD_LEVELS_H

#include "distance_map.h"
#include "texture_function.h"

/* At most this many native levels (lod 1..), as for cells. */
#define MESOI_HEIGHT_MAX_NATIVE 4
/* No level whose height field (volume) is smaller than this along s or t (or w). */
#define MESOI_HEIGHT_MIN_LEVEL_RES 4

/* One native level: a halved height field here, or a halved volume
 * (volume_levels.h builds those into the same struct). */
typedef struct mesoi_height_level {
    meso_texfn fn;     /* the halved height field (or volume), of level 0's dtype */
    meso_distmap dist; /* its distance map (distance_map.h), level 0's dtype; none without d0 */
    double sup;        /* sup over texture space of |h_l - h_0|, both filtered as the runtime samples them (0 for a volume) */
} mesoi_height_level;

/* Up to `want` (<= MESOI_HEIGHT_MAX_NATIVE) levels below `f0` (a height
 * field, or a density volume: volume_levels.h) and, when `d0` is not
 * NULL, its distance map `d0`, into out[0..*count-1]: level l halves level
 * l - 1 (each texel the mean of its 2 x 2 children, 2 x 2 x 2 for a
 * volume, quantised to the nearest stored value), its distance map has
 * d0's dims halved l times (s and t at least 1, w at least 8). Stops
 * before a side would be odd or smaller than MESOI_HEIGHT_MIN_LEVEL_RES,
 * and, for a height field, before a level whose sup reaches `stop_sup` (a
 * shell passes the highest texel: from there the base mesh alone is as
 * close); a volume's `sup` stays 0. Deterministic for any thread count. */
meso_result mesoi_height_levels_build(const meso_texfn* f0, const meso_distmap* d0, uint32_t want, double stop_sup,
                                         int threads, mesoi_height_level* out, uint32_t* count, meso_error* err);

/* sup over (s, t) of |a(s, t) - b(s, t)| for two height fields sampled
 * bilinearly with wrap (meso_texfn_sample), a's sides b's divided by a
 * power of two (so a's texel centres lie on b's half-texel lattice).
 * Exact up to double evaluation of the stored values (see the .c). */
double mesoi_height_sup_diff(const meso_texfn* a, const meso_texfn* b, int threads);

/* The levels worth a place among a file's MESOI_STANDIN_MAX_LEVELS: a
 * native level only swaps the height field (and its map), the rest of what
 * it draws (`shared` bytes) stays, and each place it takes is a simplified
 * stand-in fewer at the far end. So level l is kept only while it draws
 * from at most 9/10 of the bytes of the level before (level 0 draws
 * `level0` bytes); decided for shells and frusta alike. Frees the levels
 * after the kept ones and returns how many are kept. Counts only:
 * deterministic. */
uint32_t mesoi_height_levels_trim(mesoi_height_level* l, uint32_t count, uint64_t shared, uint64_t level0);

void mesoi_height_levels_free(mesoi_height_level* l, uint32_t count);

#endif /* MESO_HEIGHT_FIELD_LEVELS_H */
