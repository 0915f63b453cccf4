/*
 * shell_parts.h — a shell cut into parts (internal; FORMAT.md §7.11, issue
 * 14: "each part, where a kind has parts, e.g. shell patches, so a long
 * object near the camera is fine near and coarse far"). shell_parts.c says
 * how.
 */
#ifndef MESO_SHELL_PARTS_H
#define MESO_SHELL_PARTS_H

#include <stddef.h>
#include <stdint.h>

#include "bake_internal.h"
#include "mesh_chunk.h"
#include "mesh_parts.h"

typedef struct mesoi_shell_parts_input {
    const meso_mesh* standin;   /* the shell's first stand-in (mid-surface or base mesh): the base mesh's
                                   triangles, in its order */
    double standin_error;       /* that stand-in's error (its LODS record's, before rounding) */
    const meso_mesh* base;      /* the base mesh the prisms grow on (its positions) */
    const float* sdir;          /* directors per base vertex, `layers` of them (FORMAT.md §7.2 SDIR) */
    int layers;
    const float* shows;         /* what level 0 shows over each standin vertex (RGBA linear), or NULL */
    int vcol_components;        /* 4 or 1, with shows */
    int baked_normals;          /* 1: standin's normals are baked (standin_levels.h): the patches' simplified
                                   levels take them as they take the colours */
    double colour_spacing;      /* the stand-ins' colour sampling */
    uint32_t object;
    uint32_t part_triangles;    /* 0 = MESO_MESH_PARTS_TRIANGLES */
    int threads;
} mesoi_shell_parts_input;

typedef struct mesoi_shell_parts {
    uint32_t count;             /* 0: not cut (too few triangles) */
    uint32_t records, edges;
    size_t bytes;               /* of all the chunks below */
    mesoi_chunk* chunks;        /* the PRTS, PTRI, PMSH and PVCL chunks, chunk_count of them; they point into the
                                   buffers below */
    size_t chunk_count;
    uint8_t* prts;
    uint32_t* list;             /* the PTRI chunk: base triangles, part after part */
    meso_mesh_chunk* pmsh;      /* [records - count] */
    uint8_t** pvcl;             /* [records - count], NULL entries without colours */
} mesoi_shell_parts;

/* Cuts the shell's stand-in into parts (mesh_parts.c) and makes the parts'
 * chunks. Free with mesoi_shell_parts_free (also after a failure). */
meso_result mesoi_shell_parts_build(const mesoi_shell_parts_input* in, mesoi_shell_parts* out, meso_error* err);
void mesoi_shell_parts_free(mesoi_shell_parts* sp);

#endif /* MESO_SHELL_PARTS_H */
