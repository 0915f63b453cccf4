/*
 * volume_levels.h — native coarser levels of a shell drawn from a density
 * volume (FORMAT.md §7.10; issue 14: "prefiltered pyramids of the texture
 * function (height fields and volumes; the distance map of each level
 * conservative for that level's function)"). The volume is halved level by
 * level, and how far each level's surface is from level 0's is measured:
 * a two-sided Hausdorff bound in texture space, turned into object units
 * through a bound on the shell mapping's Jacobian (see the .c for the
 * argument and what it does not cover). Internal, mesoi_ prefix.
 */
#ifndef MESO_VOLUME_LEVELS_H
#define MESO_VOLUME_LEVELS_H

#include "height_field_levels.h"

/* The measurement runs on level 0's half-texel lattice, (2W)(2H)(2D) cells
 * with a double each: above this many cells (weave:128 has 2^23) a volume
 * gets no native level. */
#define MESOI_VOLUME_MAX_LATTICE ((uint64_t)1 << 24)

/* mesoi_height_levels_build for a density volume `f0` (`sup` left 0: the
 * error needs the shell, mesoi_volume_level_distances), or none when level
 * 0's lattice exceeds MESOI_VOLUME_MAX_LATTICE. */
meso_result mesoi_volume_levels_build(const meso_texfn* f0, const meso_distmap* d0, uint32_t want, int threads,
                                      mesoi_height_level* out, uint32_t* count, meso_error* err);

/* The heap mesoi_volume_level_distances holds for `f0` at its peak. */
uint64_t mesoi_volume_level_bytes(const meso_texfn* f0);

/* For each of `count` levels of `f0` (mesoi_volume_levels_build), into
 * out[l]: a bound on the two-sided Hausdorff distance between the surfaces
 * of the solids {alpha_0 >= 1/2} and {alpha_l >= 1/2}, both sampled as the
 * runtime samples them (trilinear, wrapping in s and t, clamped in w, no
 * solid outside w in [0, 1]), in the texture-space metric
 *     |(ds, dt, dw)| = sqrt((g[0] ds)^2 + (g[0] dt)^2 + (g[1] dw)^2);
 * 0 when neither has a surface, INFINITY when only one has (or level 0's
 * lattice exceeds MESOI_VOLUME_MAX_LATTICE). Stops after the first level
 * whose distance reaches `stop` (the rest stay INFINITY). */
meso_result mesoi_volume_level_distances(const meso_texfn* f0, const mesoi_height_level* levels, uint32_t count,
                                         const double g[2], double stop, int threads, double* out, meso_error* err);

/* The smallest distance mesoi_volume_level_distances can state: a lattice
 * cell's diagonal in that metric (a level whose error would not be below
 * the base mesh's even then is not worth measuring). */
double mesoi_volume_level_floor(const meso_texfn* f0, const double g[2]);

/* The scales of that metric for a shell, and the factor that turns it into
 * object units: `base` the output base mesh with its texture coordinates
 * (uvs, tiling included), `sdir` its SDIR (`layers` 1 or 2, FORMAT.md
 * §7.2), `span` its longest top - bottom. g[0] bounds |dPhi/d(s, t)| (the
 * largest singular value over the prisms), g[1] = span; *k bounds the
 * largest singular value of [dPhi/d(s, t) / g[0], dPhi/dw / g[1]] (1 to
 * sqrt(3)), so two points of a prism whose texture coordinates are r apart
 * in the metric are at most k r apart in object space. Returns 0 (and
 * INFINITY in *k) when a prism's texture triangle is degenerate. */
int mesoi_volume_level_scales(const meso_mesh* base, const float* sdir, int layers, double span, double g[2],
                              double* k);

#endif /* MESO_VOLUME_LEVELS_H */
