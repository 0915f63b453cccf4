/*
 * shell_bend.h — after repair and regrow: directors that bend before they
 * shrink (issue 15, "thickness kept"). Internal.
 *
 * Regrow (shell_regrow.h) lengthens a shortened director only along the
 * direction the field gave it. Where that direction runs into a
 * neighbour's prism or offset triangle, the director stays short, although
 * the geometry may allow much more along the vertex normal
 * (shell_allowed.h: allowed_v, half the gap along s·n_v). Bending tries,
 * for every vertex repair left shorter than allowed_v (the caller's redo),
 * 49 candidates: lengths f·allowed_v, f = 1, 7/8, .., 1/4, longest first,
 * and at each length seven directions,
 *
 *   t, normalize((1 − α) t + α s·n_v) for α = 1/4, 1/2, 3/4, 1, r, normalize(r + s·n_v)
 *
 * (t: the director's own unit direction, r: the mean unit direction of its
 * ring of neighbours, a smoothed field), and keeps the first that is longer
 * than what it has and passes the exact checks (shell_checker.h) together
 * with the other movers of its round. Candidates whose own prisms fail
 * meso_shell_prism_check are passed over before the checker (its first
 * test; at armadillo 10 % exterior 98 % of the rejected candidates, and
 * the checker's intersection tests are what costs). The movers go in rounds
 * of vertices that share no face (chosen in vertex order), so a failing
 * face has at most one mover, and the movers of failing faces go back for
 * their next candidate (two movers whose offset triangles meet both go
 * back, though either might have passed alone: conservative, and still
 * deterministic); then a second pass with the directions the first left.
 * Every accepted state passes the checks; a director never gets shorter,
 * and never longer than allowed_v up to float rounding (so never longer
 * than the requested thickness beyond it).
 * Deterministic: the rounds, the order and the checks do not depend on the
 * thread count.
 *
 * >>decided
 * - Only directors repair shortened bend. Bending every director shorter
 *   than allowed_v (Lp chords are shorter than h where the field's
 *   trajectories curve) raised the interior means more (armadillo 5 %
 *   interior 0.911 -> 0.949, fertility 0.903 -> 0.940) but replaced the
 *   field's directors at 8830 of armadillo's 14587 vertices and cost 1 s at
 *   106k triangles; it is the field's choice, not a shrink.
 * - Moving connected clusters of short vertices together (the issue's
 *   "optimise neighbouring directors jointly") was tried as a third pass: on
 *   armadillo 10 % exterior 67 -> 65 below half, elsewhere nothing; not kept.
 * - A third single pass: 67 -> 64 there for 13 % more bake time; not kept.
 *   (Both measured while r was the ring's sum, not its mean, so that
 *   r + s·n hardly turned; normalised: 67 -> 63 with two passes.)
 * - Where even 1/4 of allowed_v fails in every direction (armadillo 10 %
 *   exterior keeps a vertex at 0.007 of it), the prisms of its short
 *   neighbours invert: allowed_v, a ray bound, does not see the normals
 *   converging.
 */
#ifndef MESO_SHELL_BEND_H
#define MESO_SHELL_BEND_H

#include <stdint.h>

#include "meso_bake.h"
#include "shell_checker.h"

/* d: valid directors of one side (3 floats per vertex; sign +1 exterior,
 * −1 interior), changed in place; normals: unit vertex normals (the ones
 * the directors start from); allowed: meso_shell_allowed of this side.
 * redo: NULL, or only the vertices with redo[v] may bend (an incremental
 * re-bake). ck: the checker the directors were last checked with (its
 * verdicts are reused), or NULL. *bent (may be NULL) counts the directors
 * changed. Does nothing unless d passes the checks. */
meso_result meso_shell_bend(const meso_mesh* m, float* d, const float* normals, const double* allowed, int sign,
                            int threads, const uint8_t* redo, meso_shell_checker* ck, uint32_t* bent,
                            meso_error* err);

#endif /* MESO_SHELL_BEND_H */
