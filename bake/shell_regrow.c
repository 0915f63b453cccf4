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

/* Director cv grown to the middle of its length and hi (the shortest length
 * known to fail); 0 when there is nothing left to try. */
static int grow_half(float* cv, double hi)
{
    const double len = len3f(cv);
    if (len <= 0.0 || hi <= len * (1.0 + 1e-3))
        return 0;
    const double s = 0.5 * (len + hi) / len;
    for (int k = 0; k < 3; ++k)
        cv[k] = (float)(cv[k] * s);
    return 1;
}

/* Checks cand (d with the `moved` directors grown) and sends the moved
 * corners of failing faces back to d until no face fails. A face with one
 * moved corner blames it (hi = its failing length); with several, they go
 * back unblamed, marked in `contested` (NULL: blame them all). On return
 * cand passes the checks. */
static meso_result settle(meso_shell_checker* chk, const meso_mesh* m, const float* d, float* cand, uint8_t* moved,
                          double* hi, uint8_t* contested, uint8_t* bad, meso_error* err)
{
    const uint32_t nt = m->triangle_count;
    for (;;) {
        uint32_t nbad = 0;
        meso_result r = meso_shell_checker_bad_faces(chk, cand, bad, &nbad, err);
        if (r != MESO_OK || nbad == 0)
            return r;
        uint32_t back = 0;
        for (uint32_t f = 0; f < nt; ++f) {
            if (!bad[f])
                continue;
            const uint32_t* c = m->indices + 3 * (size_t)f;
            const int movers = moved[c[0]] + moved[c[1]] + moved[c[2]];
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = c[k];
                if (!moved[v])
                    continue;
                if (movers == 1 || !contested)
                    hi[v] = len3f(cand + 3 * (size_t)v);
                else
                    contested[v] = 1;
                memcpy(cand + 3 * (size_t)v, d + 3 * (size_t)v, 3 * sizeof(float));
                moved[v] = 0;
                ++back;
            }
        }
        if (!back) { /* a bad face with no moved corner: cannot be, d was valid */
            memcpy(cand, d, sizeof(float) * 3 * (size_t)m->vertex_count);
            return MESO_OK;
        }
    }
}

meso_result meso_shell_regrow(const meso_mesh* m, float* d, const float* target, int sign, uint32_t rounds,
                              int threads, uint32_t* grown, meso_error* err)
{
    return meso_shell_regrow_in(m, d, target, sign, rounds, threads, NULL, grown, NULL, err);
}

meso_result meso_shell_regrow_in(const meso_mesh* m, float* d, const float* target, int sign, uint32_t rounds,
                                 int threads, const uint8_t* redo, uint32_t* grown, meso_shell_checker* shared,
                                 meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    const size_t nd = 3 * (size_t)nv;
    float* cand = malloc(sizeof(float) * (nd ? nd : 1));
    float* orig = malloc(sizeof(float) * (nd ? nd : 1));
    double* hi = malloc(sizeof(double) * (nv ? nv : 1)); /* per vertex: the shortest length known to fail */
    uint8_t* bad = calloc(nt ? nt : 1, 1);
    uint8_t* moved = calloc(nv ? nv : 1, 1);
    uint8_t* contested = calloc(nv ? nv : 1, 1);
    uint8_t* taken = calloc(nt ? nt : 1, 1);
    uint32_t *vf_first = NULL, *vf = NULL; /* the faces around each vertex */
    meso_result r = cand && orig && hi && bad && moved && contested && taken
                        ? meso_vertex_faces(m, &vf_first, &vf, "regrow", err)
                        : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "regrow: out of memory");
    /* Each pass moves a few directors: the incremental checker re-tests only
     * the faces around them, with the verdicts of a full check. */
    meso_shell_checker* chk = shared;
    if (r == MESO_OK && !chk)
        r = meso_shell_checker_create(m, sign, threads, &chk, err);
    if (r == MESO_OK && redo && !shared)
        r = meso_shell_checker_prime(chk, d, redo, err);
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
            moved[v] = (uint8_t)grow_half(cand + 3 * (size_t)v, hi[v]);
            trying += moved[v];
        }
        if (!trying)
            break;
        /* Directors of faces that fail go back until no face fails; each
         * pass sends at least one back, so this ends, at worst where it
         * started. A failing face with one moved corner names the culprit:
         * its failing length is remembered. One with several cannot tell
         * which: they all go back without blame (contested) and try again
         * below, one corner per face. */
        r = settle(chk, m, d, cand, moved, hi, contested, bad, err);
        if (r == MESO_OK)
            memcpy(d, cand, sizeof(float) * nd);
        /* The contested corners, in passes of corners that share no face
         * (chosen in vertex order): now every failing face has one mover. */
        for (;;) {
            memset(taken, 0, nt ? nt : 1);
            memcpy(cand, d, sizeof(float) * nd);
            uint32_t picked = 0, chosen = 0;
            for (uint32_t v = 0; r == MESO_OK && v < nv; ++v) {
                moved[v] = 0;
                if (!contested[v])
                    continue;
                int free_ = 1;
                for (uint32_t i = vf_first[v]; i < vf_first[v + 1] && free_; ++i)
                    free_ = !taken[vf[i]];
                if (!free_)
                    continue;
                for (uint32_t i = vf_first[v]; i < vf_first[v + 1]; ++i)
                    taken[vf[i]] = 1;
                contested[v] = 0;
                ++picked;
                moved[v] = (uint8_t)grow_half(cand + 3 * (size_t)v, hi[v]);
                chosen += moved[v];
            }
            if (r != MESO_OK || !picked)
                break;
            if (!chosen)
                continue;
            r = settle(chk, m, d, cand, moved, hi, NULL, bad, err);
            if (r == MESO_OK)
                memcpy(d, cand, sizeof(float) * nd);
        }
    }
    uint32_t n = 0;
    for (uint32_t v = 0; r == MESO_OK && v < nv; ++v)
        n += memcmp(d + 3 * (size_t)v, orig + 3 * (size_t)v, 3 * sizeof(float)) != 0;
    if (grown)
        *grown = n;
    if (!shared)
        meso_shell_checker_destroy(chk);
    free(cand), free(orig), free(hi), free(bad), free(moved), free(contested), free(taken), free(vf_first), free(vf);
    return r;
}
