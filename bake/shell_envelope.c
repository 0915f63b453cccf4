/*
 * shell_envelope.c — repair of an envelope shell as it is drawn, from
 * bottom to top (shell_envelope.h).
 */
#include "shell_envelope.h"

#include <stdlib.h>
#include <string.h>

#include "shell_checker.h"
#include "shell_directors.h"
#include "shell_hybrid.h"
#include "shell_validate.h"

/* Whether the prism of face f from bottom to top is not proven valid
 * (shell_validate.h meso_shell_prism_check, sign +1: bottom = base + d1,
 * span = d0 - d1). */
static int prism_inverted(const meso_mesh* m, const float* d, uint32_t f)
{
    const size_t n = 3 * (size_t)m->vertex_count;
    const uint32_t* t = m->indices + 3 * (size_t)f;
    double b[9], w[9];
    for (int k = 0; k < 3; ++k)
        for (int j = 0; j < 3; ++j) {
            const size_t i = 3 * (size_t)t[k] + (size_t)j;
            b[3 * k + j] = (double)m->positions[i] + d[n + i];
            w[3 * k + j] = (double)d[i] - d[n + i];
        }
    return meso_shell_prism_check(b, w, 1) != 0;
}

meso_result meso_shell_envelope_repair(const meso_mesh* m, float* d, uint32_t max_rounds, int threads,
                                       uint32_t* shortened, uint32_t* rounds, uint32_t* left, meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    const size_t n = 3 * (size_t)nv;
    *shortened = *rounds = *left = 0;
    uint8_t* inverted = calloc(nt ? nt : 1, 1);
    uint8_t* touched = calloc(nv ? nv : 1, 1);
    uint8_t* now = calloc(nv ? nv : 1, 1);
    uint32_t *first = NULL, *faces = NULL;
    meso_shell_checker* ck[2] = {NULL, NULL};
    meso_result r = inverted && touched && now
                        ? meso_vertex_faces(m, &first, &faces, "envelope repair", err)
                        : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "envelope repair: out of memory");
    uint32_t bad = 0;
    for (uint32_t f = 0; r == MESO_OK && f < nt; ++f)
        bad += inverted[f] = (uint8_t)prism_inverted(m, d, f);
    while (r == MESO_OK) {
        int shrunk = 0;
        while (bad && *rounds < max_rounds) {
            memset(now, 0, nv);
            for (uint32_t f = 0; f < nt; ++f)
                if (inverted[f])
                    for (int k = 0; k < 3; ++k)
                        now[m->indices[3 * (size_t)f + (size_t)k]] = 1;
            for (uint32_t v = 0; v < nv; ++v)
                if (now[v]) {
                    touched[v] = 1;
                    for (int k = 0; k < 3; ++k) {
                        d[3 * (size_t)v + (size_t)k] *= 0.8f;
                        d[n + 3 * (size_t)v + (size_t)k] *= 0.8f;
                    }
                }
            ++*rounds;
            shrunk = 1;
            for (uint32_t v = 0; v < nv; ++v) /* only the faces around what moved */
                for (uint32_t i = now[v] ? first[v] : 0; now[v] && i < first[v + 1]; ++i) {
                    const uint32_t f = faces[i];
                    const uint8_t was = inverted[f];
                    inverted[f] = (uint8_t)prism_inverted(m, d, f);
                    bad = bad - was + inverted[f];
                }
        }
        if (bad || !shrunk)
            break;
        /* Each layer against the base again; the checkers persist, so a
         * second visit re-tests only what moved since. */
        uint32_t again = 0, layer_left = 0;
        for (int layer = 0; layer < 2 && r == MESO_OK; ++layer) {
            uint32_t sh = 0, rr = 0, l = 0;
            if (!ck[layer])
                r = meso_shell_checker_create(m, layer ? -1 : 1, threads, &ck[layer], err);
            if (r == MESO_OK)
                r = meso_shell_repair_in(m, d + (size_t)layer * n, layer ? -1 : 1, max_rounds, threads, NULL, &sh,
                                         &rr, &l, ck[layer], err);
            again += sh;
            layer_left += l;
        }
        if (r != MESO_OK || layer_left || !again) {
            *left += layer_left;
            break;
        }
        bad = 0;
        for (uint32_t f = 0; f < nt; ++f) /* the layers' repairs moved directors too */
            bad += (inverted[f] = (uint8_t)prism_inverted(m, d, f)) != 0;
    }
    *left += bad;
    for (uint32_t v = 0; v < nv; ++v)
        *shortened += touched[v];
    meso_shell_checker_destroy(ck[0]);
    meso_shell_checker_destroy(ck[1]);
    free(inverted), free(touched), free(now), free(first), free(faces);
    return r;
}
