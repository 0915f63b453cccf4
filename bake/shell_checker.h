/*
 * shell_checker.h — the exact shell checks of the hybrid and repair rounds
 * (shell_hybrid.h), incremental: a round moves only some directors, so only
 * the prisms of the faces around them and the intersection pairs with one of
 * those faces are tested again; the verdicts of the others are kept from the
 * round before. The final validation of a bake (meso_shell_validate) still
 * checks the whole shell, so a shell's validity never rests on this (an
 * update's, on the region argument of shell_update.c instead).
 */
#ifndef MESO_SHELL_CHECKER_H
#define MESO_SHELL_CHECKER_H

#include "shell_directors.h"

typedef struct meso_shell_checker meso_shell_checker;

/* A checker for directors over `m` (kept by reference; sign +1 exterior, -1
 * interior), its intersection tests split over `threads` (<= 0: all cores;
 * the verdicts do not depend on it). */
meso_result meso_shell_checker_create(const meso_mesh* m, int sign, int threads, meso_shell_checker** out,
                                      meso_error* err);
/* meso_shell_bad_faces of directors d (3 nv floats): bad[f] = 1 for each face
 * whose prism is not provably valid or whose offset triangle meets another
 * offset triangle or the base; *count their number. The first call checks
 * every face; later ones only the faces with a corner whose director differs
 * (bit for bit) from the previous call's, with the same result as a full
 * check. */
meso_result meso_shell_checker_bad_faces(meso_shell_checker* c, const float* d, uint8_t* bad, uint32_t* count,
                                         meso_error* err);
/* Start from directors d (3 nv floats) known to pass every check except
 * around the vertices with dirty[v] (an incremental re-bake, shell_update.h:
 * the previous bake's valid shell, with the edited region marked): the
 * next call re-checks only the faces with a dirty corner or a changed
 * director, as if a full check had found every other face valid. Exact
 * when no offset triangle of a clean face can meet the base or offset
 * triangles of a dirty one whose base moved — the caller's region must
 * guarantee that (shell_update.c). */
meso_result meso_shell_checker_prime(meso_shell_checker* c, const float* d, const uint8_t* dirty, meso_error* err);
/* Seconds spent in meso_shell_checker_bad_faces so far. */
double meso_shell_checker_seconds(const meso_shell_checker* c);
void meso_shell_checker_destroy(meso_shell_checker* c);

#endif /* MESO_SHELL_CHECKER_H */
