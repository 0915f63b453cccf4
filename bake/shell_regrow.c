/*
 * shell_regrow.c — give back what repair took and did not need to
 * (shell_regrow.h).
 */
#include "shell_regrow.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shell_checker.h"
#include "shell_hybrid.h"

static double len3f(const float* v)
{
    return sqrt((double)v[0] * v[0] + (double)v[1] * v[1] + (double)v[2] * v[2]);
}

meso_result meso_shell_regrow(const meso_mesh* m, float* d, const float* target, int sign, uint32_t rounds,
                              int threads, uint32_t* grown, meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    const size_t nd = 3 * (size_t)nv;
    float* cand = malloc(sizeof(float) * (nd ? nd : 1));
    float* orig = malloc(sizeof(float) * (nd ? nd : 1));
    double* hi = malloc(sizeof(double) * (nv ? nv : 1)); /* per vertex: the shortest length known to fail */
    uint8_t* bad = calloc(nt ? nt : 1, 1);
    uint8_t* moved = calloc(nv ? nv : 1, 1);
    meso_result r = cand && orig && hi && bad && moved
                        ? MESO_OK
                        : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "regrow: out of memory");
    /* Each pass moves a few directors: the incremental checker re-tests only
     * the faces around them, with the verdicts of a full check. */
    meso_shell_checker* chk = NULL;
    if (r == MESO_OK)
        r = meso_shell_checker_create(m, sign, threads, &chk, err);
    uint32_t nbad = 0;
    if (r == MESO_OK) {
        memcpy(orig, d, sizeof(float) * nd);
        for (uint32_t v = 0; v < nv; ++v)
            hi[v] = len3f(target + 3 * (size_t)v);
        r = meso_shell_checker_bad_faces(chk, d, bad, &nbad, err);
    }
    /* Only a valid shell is grown: every accepted state stays valid. */
    for (uint32_t round = 0; r == MESO_OK && nbad == 0 && round < rounds; ++round) {
        /* Every shortened director tries the middle of what it has and
         * the shortest length known to fail (at first: its length before
         * repair). */
        memcpy(cand, d, sizeof(float) * nd);
        uint32_t trying = 0;
        for (uint32_t v = 0; v < nv; ++v) {
            float* cv = cand + 3 * (size_t)v;
            const double len = len3f(cv);
            moved[v] = 0;
            if (len <= 0.0 || hi[v] <= len * (1.0 + 1e-3))
                continue;
            const double s = 0.5 * (len + hi[v]) / len;
            for (int k = 0; k < 3; ++k)
                cv[k] = (float)(cv[k] * s);
            moved[v] = 1;
            ++trying;
        }
        if (!trying)
            break;
        /* Directors of faces that fail go back (and remember the failing
         * length) until no face fails; each pass sends at least one back,
         * so this ends, at worst where it started. */
        for (;;) {
            r = meso_shell_checker_bad_faces(chk, cand, bad, &nbad, err);
            if (r != MESO_OK || nbad == 0)
                break;
            uint32_t back = 0;
            for (uint32_t f = 0; f < nt; ++f) {
                if (!bad[f])
                    continue;
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = m->indices[3 * (size_t)f + k];
                    if (!moved[v])
                        continue;
                    hi[v] = len3f(cand + 3 * (size_t)v);
                    memcpy(cand + 3 * (size_t)v, d + 3 * (size_t)v, 3 * sizeof(float));
                    moved[v] = 0;
                    ++back;
                }
            }
            if (!back) { /* a bad face with no moved corner: cannot be, d was valid */
                memcpy(cand, d, sizeof(float) * nd);
                nbad = 0;
                break;
            }
        }
        if (r == MESO_OK)
            memcpy(d, cand, sizeof(float) * nd);
    }
    uint32_t n = 0;
    for (uint32_t v = 0; r == MESO_OK && v < nv; ++v)
        n += memcmp(d + 3 * (size_t)v, orig + 3 * (size_t)v, 3 * sizeof(float)) != 0;
    if (grown)
        *grown = n;
    meso_shell_checker_destroy(chk);
    free(cand), free(orig), free(hi), free(bad), free(moved);
    return r;
}
