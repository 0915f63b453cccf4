/*
 * shell_envelope.h — repair of an envelope shell as it is drawn (issue 15;
 * FORMAT.md §7.2 kind envelope). Internal.
 *
 * An envelope has two layers: the top at base + d0 (outwards) and the
 * bottom at base + d1 (inwards), and its prisms run from bottom to top,
 * Phi = bottom + w (top - bottom). The bake computes, repairs and checks
 * each layer against the base alone (shell_hybrid.h), which does not make
 * the prism from bottom to top valid: where the two layers' directors lean
 * apart, the bottom triangle tilts against the span top - bottom and that
 * prism inverts, though both halves are fine. Measured before this stage:
 * spot_uv at 5 % left 18 such prisms and at 10 % 51, the bunny 6 and 17,
 * the armadillo 86 and 397, and the bake was refused (E3115).
 *
 * meso_shell_envelope_repair shortens both directors of the corners of
 * every inverted bottom-to-top prism by 0.8 a round (the checks of
 * shell_validate.c on the bottom mesh with the span as directors), then
 * repairs each layer against the base again (whose checks a shorter
 * director may in rare cases fail), and again while either shortened
 * anything. It ends: shrinking both layers by a factor a leaves a prism
 * whose corner coefficients are a N0 . (d0 - d1) + O(a^2), N0 the base
 * normal, and both halves being valid means N0 . d0 > 0 and N0 . d1 < 0 at
 * every corner (shell_validate.h, the w = 0 coefficients), so the prism is
 * valid once a is small enough.
 */
#ifndef MESO_SHELL_ENVELOPE_H
#define MESO_SHELL_ENVELOPE_H

#include <stdint.h>

#include "meso_bake.h"

/* d: 6 nv floats, layer 0 (top) then layer 1 (bottom), both valid against
 * the base (each passes shell_checker.h with sign +1 and -1), changed in
 * place. max_rounds: the budget of each repair (MESO_SHELL_REPAIR_ROUNDS).
 * *shortened: the vertices it shortened for the bottom-to-top prisms (the
 * layers' repairs after them are not counted); *rounds: its rounds on
 * those prisms; *left: prisms still inverted plus faces the
 * layers' repairs left bad (0 when it succeeded). Deterministic for any
 * thread count. */
meso_result meso_shell_envelope_repair(const meso_mesh* m, float* d, uint32_t max_rounds, int threads,
                                       uint32_t* shortened, uint32_t* rounds, uint32_t* left, meso_error* err);

#endif /* MESO_SHELL_ENVELOPE_H */
