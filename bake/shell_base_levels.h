/*
 * shell_base_levels.h — coarser base meshes of a shell, each with its
 * directors (internal; FORMAT.md §7.10, issue 14: "coarser base meshes with
 * their directors"). shell_base_levels.c says how the meshes are made and
 * how far their shells are from level 0's.
 */
#ifndef MESO_SHELL_BASE_LEVELS_H
#define MESO_SHELL_BASE_LEVELS_H

#include <stdint.h>

#include "meso_bake.h"

/* At most this many coarser base meshes. */
#define MESOI_SHELL_BASE_LEVELS_MAX 3

typedef struct mesoi_shell_base_level {
    meso_mesh mesh;    /* a subset of the base's vertices (positions, normals, uvs), new triangles */
    float* sdir;       /* the kept vertices' directors, `layers` blocks of 3 * vertex_count (FORMAT.md §7.2) */
    float* thick;      /* the kept vertices' STHK values */
    double distance;   /* max over texture space (u, v) and w in [0, 1] of |Φ_level − Φ_base|: every point of
                          this level's shell lies that close to the point of the base's over the same (u, v, w) */
} mesoi_shell_base_level;

typedef struct mesoi_shell_base_levels_input {
    const meso_mesh* base; /* the shell's base mesh as its MESH chunk has it: uvs per vertex, split at seams */
    const float* sdir;     /* its directors, `layers` blocks (FORMAT.md §7.2 SDIR) */
    int layers;            /* 1 (top = position + layer 0, bottom = position) or 2 (bottom = position + layer 1) */
    const float* thick;    /* STHK per vertex */
    uint32_t max_levels;   /* at most this many (<= MESOI_SHELL_BASE_LEVELS_MAX) */
    double limit;          /* a level whose distance reaches this is not kept, nor any after it */
} mesoi_shell_base_levels_input;

/* The coarser base meshes, finest first: *levels gets *count entries.
 * Where the chain stopped before max_levels other than by running out of
 * triangles to halve, *why says why (a static string; else NULL), and
 * *too_far is the distance of a level not kept for reaching `limit` (else
 * -1). Free with mesoi_shell_base_levels_free. Without meshoptimizer: none
 * (why says so). */
meso_result mesoi_shell_base_levels_build(const mesoi_shell_base_levels_input* in, mesoi_shell_base_level** levels,
                                          uint32_t* count, const char** why, double* too_far, meso_error* err);
void mesoi_shell_base_levels_free(mesoi_shell_base_level* levels, uint32_t count);

/* The largest |Φ_coarse − Φ_fine| over the texture space both cover (the
 * max over the vertices of their uv triangulations' overlay, w = 0 and 1),
 * for meshes whose vertices carry bottoms (`bottom`, 3 per vertex) and
 * spans (`span` = top − bottom). `chart` and `coarse_chart` give each
 * triangle its region of texture space (one orientation of one uv chart);
 * only triangles of one region are compared. Exposed for the tests (a
 * brute-force sampler checks it). Returns a negative value when out of
 * memory. */
double mesoi_shell_map_distance(const meso_mesh* fine, const float* fine_bottom, const float* fine_span,
                                const uint32_t* chart, const meso_mesh* coarse, const float* coarse_bottom,
                                const float* coarse_span, const uint32_t* coarse_chart);

#endif /* MESO_SHELL_BASE_LEVELS_H */
