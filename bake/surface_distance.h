/*
 * surface_distance.h — a conservative two-sided (Hausdorff) distance between
 * two triangle meshes' surfaces (internal). The error of a mesh level of
 * detail (mesh_levels.c, FORMAT.md §7.10 `error`) is measured with it.
 *
 * What is computed: samples on each surface — every triangle subdivided
 * into n × n similar sub-triangles, n = ceil(longest edge / spacing), and
 * their corners (the triangle's vertices among them) — and for each sample
 * the exact distance to the other mesh (Ericson's closest point on a
 * triangle over triangle_grid.c's grid). Every point of a triangle is
 * within longest edge / sqrt(3) of one corner of its sub-triangle (the
 * circumradius of an acute triangle is at most that, and the farthest point
 * of an obtuse one is at most half its longest edge away), and the distance
 * to a surface is 1-Lipschitz, so
 *
 *     bound = max(largest sample distance A -> B, B -> A) + radius,
 *     radius = max over sub-triangles of their longest edge / sqrt(3)
 *
 * is an upper bound of the Hausdorff distance (up to rounding), and exceeds
 * it by at most 2 * radius (a sample's distance is the distance of a point
 * of the surface). Deterministic: maxima do not depend on the thread count.
 */
#ifndef MESO_SURFACE_DISTANCE_H
#define MESO_SURFACE_DISTANCE_H

#include "meso_bake.h"
#include "triangle_grid.h"

/* The bound above between the surfaces of `a` and `b` (both with at least
 * one triangle), samples at `spacing` (> 0). *radius (may be NULL) gets
 * the sampling radius included in *bound. */
meso_result meso_surface_distance(const meso_mesh* a, const meso_mesh* b, double spacing, int threads, double* bound,
                                  double* radius, meso_error* err);

/* A reference mesh measured against many others (the levels of a chain
 * against level 0): its samples' coordinates and its grid, built once over
 * its own bounds. A mesh measured against it that reaches outside those
 * bounds is measured as meso_surface_distance does (both grids anew). */
typedef struct meso_surface_ref {
    const meso_mesh* mesh; /* borrowed */
    double* xyz;
    double lo[3], hi[3];
    mesoi_tri_grid grid;
    int built;
} meso_surface_ref;

meso_result meso_surface_ref_build(const meso_mesh* m, meso_surface_ref* ref, meso_error* err);

/* meso_surface_distance(a, ref->mesh, ...), the same bound. */
meso_result meso_surface_distance_to_ref(const meso_mesh* a, const meso_surface_ref* ref, double spacing,
                                         int threads, double* bound, double* radius, meso_error* err);

void meso_surface_ref_free(meso_surface_ref* ref);

/* The mean edge length of `m` (every triangle's three edges; 0 without
 * triangles): the spacing mesh_levels.c derives from level 0. */
double meso_mesh_mean_edge(const meso_mesh* m);

#endif /* MESO_SURFACE_DISTANCE_H */
