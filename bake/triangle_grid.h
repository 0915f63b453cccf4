/*
 * triangle_grid.h — exact unsigned distance from points to a triangle mesh
 * through a uniform grid of triangles (internal, mesoi_ prefix). Used by
 * meso_skeleton_from_mesh for the model -> mesh direction of its two-sided
 * error (skeleton_from_mesh.h, "What is measured"); why it is not CGAL's
 * AABB tree is at the top of triangle_grid.c.
 */
#ifndef MESO_TRIANGLE_GRID_H
#define MESO_TRIANGLE_GRID_H

#include <stdint.h>

#include "meso_bake.h"

/* Triangles binned by their bounding boxes into cubic cells; a query grows
 * shells of cells around the point until no unseen triangle can be closer. */
typedef struct mesoi_tri_grid {
    const double* xyz;   /* 3 per vertex (borrowed) */
    const uint32_t* tri; /* 3 per triangle (borrowed) */
    uint32_t nt;
    double lo[3], cell;
    int dim[3];
    uint32_t* start; /* dim[0]*dim[1]*dim[2] + 1 */
    uint32_t* items;
    uint32_t* stamp; /* per triangle: the last query that tested it */
    uint32_t query;
} mesoi_tri_grid;

/* A grid over [lo, hi], which must hold the mesh and every query point;
 * about one triangle per surface cell, at most 2^24 cells. The mesh
 * arrays are borrowed until mesoi_tri_grid_free. On failure `g` is freed. */
meso_result mesoi_tri_grid_build(const double* xyz, const uint32_t* tri, uint32_t nt, const double lo[3],
                                 const double hi[3], mesoi_tri_grid* g, meso_error* err);

/* Unsigned distance from p to the nearest triangle (exact up to rounding;
 * not thread-safe: the query stamps live in `g`). */
double mesoi_tri_grid_distance(mesoi_tri_grid* g, const double p[3]);

/* The same, and the nearest triangle (the lowest index among equally near
 * ones) with the barycentrics of its 2nd and 3rd corners at the closest
 * point (the 1st: 1 - bw[0] - bw[1]). */
double mesoi_tri_grid_closest(mesoi_tri_grid* g, const double p[3], uint32_t* tri, double bw[2]);

/* The same distance when it is below r; otherwise some value >= r (the
 * search stops once every triangle nearer than r has been seen). */
double mesoi_tri_grid_distance_within(mesoi_tri_grid* g, const double p[3], double r);

/* Distance from p to triangle f of the grid's mesh (the same exact
 * computation a query makes). */
double mesoi_tri_grid_triangle_distance(const mesoi_tri_grid* g, uint32_t f, const double p[3]);

void mesoi_tri_grid_free(mesoi_tri_grid* g);

#endif /* MESO_TRIANGLE_GRID_H */
