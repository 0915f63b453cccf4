/*
 * shell_hybrid.h — hybrid directors (the Lp paper's own future work, §6):
 * plain normal displacement wherever it is provably safe, the Lp-averaged
 * field only where it is needed.
 */
#ifndef MESO_SHELL_HYBRID_H
#define MESO_SHELL_HYBRID_H

#include "shell_checker.h"
#include "shell_directors.h"

typedef struct meso_hybrid_stats {
    uint32_t vertices_lp;     /* vertices whose director was traced through the field */
    uint32_t vertices_normal; /* vertices that kept normal displacement */
    uint32_t rounds;          /* validate-and-grow rounds */
    uint32_t bad_faces_left;  /* faces still failing after the last round */
    double seconds_checks;    /* of the directors' time: the exact checks of the rounds (shell_checker.h) */
} meso_hybrid_stats;

/* Faces whose prism (base + w d) is not provably valid: det J not proven
 * positive (sign: +1 exterior, -1 interior), or whose offset triangle
 * intersects another offset triangle or the base surface (exact, CGAL).
 * bad[f] = 1 for such faces; *count gets their number. */
meso_result meso_shell_bad_faces(const meso_mesh* m, const float* d, int sign, uint8_t* bad, uint32_t* count,
                                 meso_error* err);

/* Directors for one side (sign * normals, thickness opt->thickness):
 *  1. normal displacement everywhere;
 *  2. the vertices of bad faces, and one ring around them, switch to the
 *     Lp field (a ring, so the switch happens away from the failure);
 *  3. validate again; vertices of faces still bad join, with their ring;
 *     repeat until no face is bad or no vertex is left to switch.
 * Normal displacement is kept only where the final shell passes the exact
 * checks, which is the "provably safe" of the issue. That is
 * MESO_DIRECTORS_HYBRID; MESO_DIRECTORS_LP traces every vertex,
 * MESO_DIRECTORS_NORMAL keeps normal displacement everywhere. lp_mask (nv, may be NULL) gets 1 for Lp vertices. */
meso_result meso_shell_side_directors(const meso_lp_field* field, const meso_mesh* m, const float* normals, int sign,
                                      const meso_trace_options* opt, meso_shell_directors mode, int threads, float* d,
                                      uint8_t* lp_mask, meso_hybrid_stats* hs, meso_trace_stats* ts,
                                      meso_error* err);
/* The same for an incremental re-bake (shell_update.h): only the vertices
 * with redo[v] get directors (normal, traced, smoothed); the others keep
 * what d holds on entry, which must be a shell that passed every check
 * outside the redo region (the previous bake's). The rounds check only
 * the faces around the redo region (meso_shell_checker_prime). redo NULL:
 * meso_shell_side_directors. ck: NULL, or a checker
 * (shell_checker.h) for this mesh and side that the caller made (and
 * primed with redo) and keeps using: repair and regrow then start from
 * the verdicts the last round left instead of checking every face again. */
meso_result meso_shell_side_directors_in(const meso_lp_field* field, const meso_mesh* m, const float* normals,
                                         int sign, const meso_trace_options* opt, meso_shell_directors mode,
                                         int threads, const uint8_t* redo, float* d, uint8_t* lp_mask,
                                         meso_hybrid_stats* hs, meso_trace_stats* ts, meso_shell_checker* ck,
                                         meso_error* err);

/* Repair rounds of a bake. Each round a director shortened is 0.8 of what
 * it was, and 72 rounds take one below a float's precision of its own
 * length; faces turn bad in a cascade (a director shortened lets its
 * neighbour's offset cross), so a director may start shrinking late. 100
 * leaves that room. It was 30: a 0.0002 slot under a 0.087 shell needed 31
 * rounds (a 2e-5 one needs 40: tests/unit/test_shell_repair.c), and a
 * smoothed 94k-triangle spot at 5 % needed 32 and was refused (E3115) with
 * 10 faces still bad. A bake that converges sooner stops sooner: the cap
 * costs nothing there. */
#define MESO_SHELL_REPAIR_ROUNDS 100

/* Repair (issue #4, --repair): shorten the directors of the vertices of
 * still-bad faces by a factor 0.8 per round, until no face is bad or
 * max_rounds pass. Shorter directors can only remove folds and collisions
 * that the thickness caused; they give up thickness locally, which the
 * report then shows (thickness_ratio_min/mean). *shortened counts the
 * vertices touched, *bad_left the faces still bad at the end. Each round
 * re-checks only the faces whose directors moved (shell_checker.h), on
 * `threads` threads (<= 0: all cores; the result does not depend on it). */
meso_result meso_shell_repair(const meso_mesh* m, float* d, int sign, uint32_t max_rounds, int threads,
                              uint32_t* shortened, uint32_t* rounds, uint32_t* bad_left, meso_error* err);
/* The same, changing only the directors of vertices with redo[v], the rest
 * known valid (as for meso_shell_side_directors_in); redo NULL: all. ck:
 * NULL or the caller's checker (as for meso_shell_side_directors_in). */
meso_result meso_shell_repair_in(const meso_mesh* m, float* d, int sign, uint32_t max_rounds, int threads,
                                 const uint8_t* redo, uint32_t* shortened, uint32_t* rounds, uint32_t* bad_left,
                                 meso_shell_checker* ck, meso_error* err);

#endif
