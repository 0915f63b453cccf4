/*
 * shell_regrow.h — after repair: give back the length repair took and did
 * not need (issue 15, "thickness kept"). Internal.
 *
 * Repair (shell_hybrid.h) shortens all three directors of every bad face by
 * 0.8 a round, though often one of them alone caused the fault; and it
 * stops at the first valid shell. Regrowing bisects, per vertex, between
 * its length now (valid) and its length before repair: each round every
 * shortened director tries the midpoint of what it has and the shortest
 * length known to fail; the exact checks (shell_checker.h) name the faces
 * that fail and their moved directors go back, until no face fails. A
 * failing face with one moved corner blames it (its failing length is
 * remembered); one with several moved corners cannot say which, so those
 * go back unblamed and try again in passes of corners that share no face
 * (chosen in vertex order), where every failure has one culprit. Blaming
 * all corners of a face, as a first version did, stopped innocent
 * directors short. So every accepted
 * state is valid, and no director grows past its length before repair
 * (the field's choice, at most the requested thickness). A bake regrows
 * exterior and interior shells; not envelopes, whose two layers are each
 * checked against the base alone, so regrowing could make them meet.
 */
#ifndef MESO_SHELL_REGROW_H
#define MESO_SHELL_REGROW_H

#include <stdint.h>

#include "meso_bake.h"
#include "shell_checker.h"

/* Bisection rounds of a bake (bake_shell.c): the last step is 1/64 of what
 * repair took. */
#define MESO_SHELL_REGROW_ROUNDS 6

/* d: the repaired directors (3 floats per vertex; side sign +1 exterior,
 * −1 interior), grown in place; target: the directors before repair.
 * Does nothing unless d passes the exact checks (shell_checker.h, re-testing
 * only the faces around the directors a pass moved). rounds: bisection
 * steps. threads: the checks' (<= 0: all cores; never changes the result).
 * *grown (may be NULL) counts the directors changed. Deterministic. */
meso_result meso_shell_regrow(const meso_mesh* m, float* d, const float* target, int sign, uint32_t rounds,
                              int threads, uint32_t* grown, meso_error* err);
/* The same where only the vertices with redo[v] may have been shortened and
 * the rest of d is known valid (an incremental re-bake, shell_update.h): the
 * first check covers only the faces around redo (meso_shell_checker_prime).
 * redo NULL: meso_shell_regrow. ck: NULL, or the checker repair used (then
 * the first check re-tests only what changed since its last call; redo is
 * then the caller's to prime). */
meso_result meso_shell_regrow_in(const meso_mesh* m, float* d, const float* target, int sign, uint32_t rounds,
                                 int threads, const uint8_t* redo, uint32_t* grown, meso_shell_checker* ck,
                                 meso_error* err);

#endif /* MESO_SHELL_REGROW_H */
