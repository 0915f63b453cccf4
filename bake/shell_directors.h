/*
 * shell_directors.h — shell directors (direction x thickness per base vertex)
 * by the adaptive explicit Euler integration of the Lp-averaged distance
 * gradient (volume-textures-lp-averaged-shells.md §4.1-4.2), plus plain
 * normal displacement. The hybrid choice between the two is in
 * shell_hybrid.c; validation in shell_validate.c.
 */
#ifndef MESO_SHELL_DIRECTORS_H
#define MESO_SHELL_DIRECTORS_H

#include "lp_distance.h"
#include "meso_bake.h"

/* meso_shell_kind (exterior, interior, envelope) and meso_shell_directors
 * (hybrid, lp, normal) are public: meso_bake.h. */

typedef struct meso_trace_options {
    double thickness;   /* h, mesh units, > 0 */
    double angle_tol;   /* radians: largest turn of the field per accepted step (default 5 degrees) */
    double first_step;  /* fraction of h of the first trial step (default 1/8) */
    double min_step;    /* fraction of h below which a step is accepted as is (default 1/1024) */
    double theta;       /* Barnes-Hut opening angle (<= 0: exact summation) */
    double near_radius; /* triangles closer than this are integrated exactly (0: θ decides alone) */
    double cutoff;      /* mesh units: integrate only the surface within this distance of x, the
                         * paper's localisation (meso_lp_eval_local; bakes pass 2h); 0: all of
                         * it. Overrides near_radius. */
    int smooth_iterations; /* Laplacian smoothing rounds of traced directors (shell_hybrid.c) */
    /* Optional progress report from the tracing loop (called by one thread
     * at a time, about every 1 %, with done <= total vertices). */
    void (*progress)(void* user, uint64_t done, uint64_t total);
    void* progress_user;
} meso_trace_options;

typedef struct meso_trace_stats {
    uint64_t evaluations; /* field evaluations */
    uint64_t steps;       /* accepted Euler steps */
    uint64_t halvings;    /* rejected trial steps */
} meso_trace_stats;

/* Follow the gradient of the Lp-averaged distance from the surface point x0,
 * leaving it along the unit vector n (the gradient coincides with the
 * surface normal on the surface, §4.1), for parameter length h; write the
 * straight director d = F(x0, h) - x0. The field must be built over the
 * same surface (plus artificial boundary faces). Thread-safe. */
meso_result meso_shell_trace(const meso_lp_field* field, const double x0[3], const double n[3],
                             const meso_trace_options* opt, double d[3], meso_trace_stats* stats);

/* The field's surface: the base mesh plus, for open meshes, one artificial
 * face strip along every boundary (§4.1 "Boundaries"): each boundary vertex
 * v gets a copy v + h t_v, with t_v the unit tangent across the boundary. */
typedef struct meso_field_surface {
    float* positions; /* 3 * vertex_count */
    uint32_t* indices;
    uint32_t vertex_count, triangle_count;
    uint32_t artificial_faces;
} meso_field_surface;

/* boundary: directed boundary edges (a, b), face on the left, as from
 * meso_mesh_topology. normals: unit vertex normals. */
meso_result meso_field_surface_build(const meso_mesh* m, const float* normals, const uint32_t* boundary,
                                     uint32_t boundary_edges, double h, meso_field_surface* out, meso_error* err);
void meso_field_surface_free(meso_field_surface* s);

/* Directors for every vertex of `m` with the field: d[3*i..] for vertex i,
 * leaving along sign * normal_i. `mask` (may be NULL) selects the vertices to
 * trace; the others are left untouched. Runs on `threads` threads (0: all);
 * each vertex is independent, so the result does not depend on the count. */
meso_result meso_shell_trace_all(const meso_lp_field* field, const meso_mesh* m, const float* normals, double sign,
                                 const meso_trace_options* opt, const uint8_t* mask, int threads, float* d,
                                 meso_trace_stats* stats, meso_error* err);

/* Unit vertex normals: angle-weighted average of face normals (robust to
 * uneven triangulations); vertices without faces get (0, 0, 1). */
meso_result meso_vertex_normals(const meso_mesh* m, float* normals, meso_error* err);

/* The faces around each vertex (CSR, in face order: deterministic): those
 * of v are faces[first[v] .. first[v + 1]). *first (vertex_count + 1) and
 * *faces (3 triangle_count) are malloc'd, the caller's to free; both NULL
 * when out of memory (MESO_ERR_OUT_OF_MEMORY, message naming `what`). */
meso_result meso_vertex_faces(const meso_mesh* m, uint32_t** first, uint32_t** faces, const char* what,
                              meso_error* err);

#endif
