/*
 * frustum_reference_internal.h — what frusta_model_reference.c (models,
 * files, rendering) takes from frustum_reference.c (one segment). Internal.
 */
#ifndef MESO_FRUSTUM_REFERENCE_INTERNAL_H
#define MESO_FRUSTUM_REFERENCE_INTERNAL_H

#include <stdint.h>

#include "frustum_reference.h"

/* A sphere holding the segment's solid (its outer cone's when `relief` is
 * on for it); 0 when no bound exists (the segment is then always tested). */
int mesoi_ref_segment_bound(const meso_ref_frustum* f, const meso_ref_relief* relief, double c[3], double* rad);

/* Nearest hit of the segment in [tmin, tmax], with its relief when `relief`
 * is on for it (samples: the relief search's count, accumulated). */
int mesoi_ref_segment_intersect(const meso_ref_frustum* f, const meso_ref_relief* relief, const double o[3],
    const double d[3], double tmin, double tmax, meso_ref_frustum_hit* hit, uint32_t* samples);

/* Ray parameters where o + t d meets the sphere, ascending; their count. */
int mesoi_ref_ray_sphere(const double c[3], double rad, const double o[3], const double d[3], double t[2]);

#endif /* MESO_FRUSTUM_REFERENCE_INTERNAL_H */
