/*
 * shell_update.h — incremental re-bake of a shell after a local edit of its
 * base mesh (`mesobake shell --update OLD.meso`; volume-textures-lp-averaged-
 * shells.md §6, "Deformations": recompute only the part within the field's
 * influence distance of the modified surface). Internal to bake_shell.c.
 */
#ifndef MESO_SHELL_UPDATE_H
#define MESO_SHELL_UPDATE_H

#include <stdint.h>

#include "bake_internal.h"
#include "mesh_chunk.h"
#include "shell_checker.h"
#include "shell_validate.h"

/* What an update keeps from OLD and what it recomputes. */
typedef struct mesoi_shell_prior {
    float* d;              /* layers x 3 nv: OLD's directors per mesh vertex, in the bake's layer order
                              (exterior: outward; interior: inward; envelope: top, then bottom) */
    uint8_t* redo;         /* nv: 1 = recompute this vertex's directors */
    uint8_t* moved_at;     /* nv: 1 = this vertex's position differs from OLD's */
    uint32_t moved;        /* vertices whose position differs from OLD's */
    uint32_t redo_count;   /* vertices recomputed */
    double radius;         /* the influence radius the region was grown by (mesh units) */
    double moved_max;      /* the farthest any vertex moved (mesh units, rounded up) */
    /* OLD's stand-in chain (its levels 2.., the simplified base meshes:
     * standin_levels.h), which an update may keep (bake_shell.c,
     * "Stand-ins of an update"); chain_count 0 when OLD has none. */
    uint32_t chain_count;
    int chain_levels;      /* OLD's `levels` option (META.parameters.levels), -1 when not recorded */
    double chain_moved;    /* how far OLD's chain's base mesh had moved since it was simplified
                              (OLD's report: update.chain_moved, 0 when absent) */
    meso_mesh_chunk chain_chunk[MESO_BAKE_SHELL_MAX_LEVELS]; /* the MESH chunks as stored */
    double chain_own[MESO_BAKE_SHELL_MAX_LEVELS];  /* each one's bound against OLD's base mesh */
    float chain_bbox[MESO_BAKE_SHELL_MAX_LEVELS][6];
    uint32_t chain_triangles[MESO_BAKE_SHELL_MAX_LEVELS];
} mesoi_shell_prior;

/* Read OLD (`path`: one shell object, validated in full, written without
 * defects) and match it to the edited mesh m (nv mesh vertices; its output
 * vertices are out_source[o] for o < nv_out with triangles out_indices, or
 * the mesh itself when out_source is NULL). Refuses, with a code naming the
 * difference: a file that is not one valid shell (E3116), bake parameters
 * that differ (E3117: kind, directors, p, theta, angle tolerance, smoothing,
 * repair, thickness), a different topology (E3118: vertex count or
 * triangles), or an OLD written with defects (E3119). h_side: each side's
 * thickness. */
meso_result mesoi_shell_prior_load(const char* path, const meso_bake_shell_options* a, double* h,
                                   const meso_mesh* m, const uint32_t* out_source, const uint32_t* out_indices,
                                   uint32_t nv_out, mesoi_shell_prior* out, meso_error* err);
void mesoi_shell_prior_free(mesoi_shell_prior* p);

/* Growth passes of an update's region before it falls back to recomputing
 * every vertex (shell_update.c, "Growth"). */
enum { MESOI_SHELL_UPDATE_GROWTH_PASSES = 3 };

/* After an update's rounds on one side (directors d, ck the checker they
 * used): the faces still bad that have a kept corner (p->redo 0) add their
 * corners and those corners' 1-ring to p->redo (and p->redo_count);
 * *added: how many vertices that added (0: nothing to grow). */
meso_result mesoi_shell_update_grow(const meso_mesh* m, meso_shell_checker* ck, const float* d, mesoi_shell_prior* p,
                                    uint32_t* added, meso_error* err);

/* The base's self-intersection test of an update (E3114 when it fails, as
 * a full bake's): only the triangle pairs with a moved corner (OLD's base,
 * which mesobake shell checked, holds the rest). */
meso_result mesoi_shell_update_base_check(const meso_mesh* m, const mesoi_shell_prior* p, const char* path,
                                          int threads, meso_error* err);

/* The final validation of an update's exterior or interior shell (directors
 * d, sign +1 / -1, per-side thickness h): every prism and the thickness
 * ratio as meso_shell_validate, the intersections only of the faces with a
 * recomputed corner (shell_update.c says why that is the whole shell's
 * count). *done = 0 when the argument does not apply (no CGAL, or a kept
 * director too long for the region's radius): validate in full then. */
meso_result mesoi_shell_update_validate(const meso_mesh* m, const float* d, double h, int sign,
                                        const mesoi_shell_prior* p, int threads, meso_shell_report* out, int* done,
                                        meso_error* err);

#endif /* MESO_SHELL_UPDATE_H */
