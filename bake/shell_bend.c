/*
 * shell_bend.c — directors that bend before they shrink (shell_bend.h).
 */
#include "shell_bend.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shell_directors.h"
#include "shell_validate.h"

#define BEND_ANGLES 7  /* t, t turned to s·n by α = 1/4, .., 1, the ring's mean r, r + s·n */
#define BEND_LENGTHS 7 /* f = 1, 7/8, .., 1/4 */
#define BEND_CANDIDATES (BEND_ANGLES * BEND_LENGTHS)
#define BEND_PASSES 2

static double len3(const double* v)
{
    return sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
}

static double len3f(const float* v)
{
    const double w[3] = {v[0], v[1], v[2]};
    return len3(w);
}

/* Candidate k of vertex v (longest first, the field's direction first at
 * each length) into out; its length. t: v's unit direction at the start. */
static double candidate(uint32_t k, const double* t, const double* ring, const float* n, int sign, double allowed,
                        float* out)
{
    const double f = 1.0 - 0.125 * (double)(k / BEND_ANGLES);
    const uint32_t a = k % BEND_ANGLES;
    double w[3];
    for (int i = 0; i < 3; ++i) {
        const double sn = sign * (double)n[i];
        w[i] = a < 5 ? (1.0 - 0.25 * a) * t[i] + 0.25 * a * sn : a == 5 ? ring[i] : ring[i] + sn;
    }
    const double l = len3(w);
    if (!(l > 1e-12))
        return 0.0;
    for (int i = 0; i < 3; ++i)
        out[i] = (float)(w[i] / l * f * allowed);
    return len3f(out);
}

/* The faces around each vertex (CSR) and the bend's state. */
typedef struct bend {
    const meso_mesh* m;
    const float* normals;
    const double* allowed;
    int sign;
    float *d, *cand;
    double *dir, *ring; /* per vertex at the pass's start: its unit direction, its neighbours' mean one */
    uint32_t *vf_first, *vf;
    uint8_t* next; /* per vertex: its next candidate; BEND_CANDIDATES = not a mover, or done */
    uint8_t *moved, *changed, *bad, *taken;
    meso_shell_checker* chk;
} bend;

/* Do the prisms of v's faces pass meso_shell_prism_check with the
 * directors of c? (The checker's first test, without its intersection
 * tests.) */
static int prisms_valid(const bend* b, const float* c, uint32_t v)
{
    const meso_mesh* m = b->m;
    for (uint32_t i = b->vf_first[v]; i < b->vf_first[v + 1]; ++i) {
        const uint32_t* t = m->indices + 3 * (size_t)b->vf[i];
        double p[9], w[9];
        for (int k = 0; k < 3; ++k)
            for (int j = 0; j < 3; ++j) {
                p[3 * k + j] = m->positions[3 * (size_t)t[k] + j];
                w[3 * k + j] = c[3 * (size_t)t[k] + j];
            }
        if (meso_shell_prism_check(p, w, b->sign))
            return 0;
    }
    return 1;
}

/* Puts v's candidate next[v] into cand; 1 if it is longer than what v has
 * and v's prisms pass with it, else cand[v] is restored. */
static int vertex_try(bend* b, uint32_t v)
{
    float* cv = b->cand + 3 * (size_t)v;
    const float* dv = b->d + 3 * (size_t)v;
    if (candidate(b->next[v], b->dir + 3 * (size_t)v, b->ring + 3 * (size_t)v, b->normals + 3 * (size_t)v, b->sign,
                  b->allowed[v], cv) > len3f(dv) * (1.0 + 1e-3) &&
        prisms_valid(b, b->cand, v))
        return 1;
    memcpy(cv, dv, 3 * sizeof(float));
    return 0;
}

/* One pass over the movers (next[v] < BEND_CANDIDATES), in rounds of
 * movers that share no face: each takes its first candidate (longest first)
 * that keeps its own prisms valid; a face that fails the exact checks sends
 * its one mover back to take its next candidate in a later round; the
 * others keep theirs and are done. */
static meso_result bend_pass(bend* b, meso_error* err)
{
    const meso_mesh* m = b->m;
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    const size_t nd = 3 * (size_t)nv;
    memcpy(b->cand, b->d, sizeof(float) * nd);
    for (;;) {
        memset(b->taken, 0, nt ? nt : 1);
        uint32_t movers = 0;
        for (uint32_t v = 0; v < nv; ++v) {
            b->moved[v] = 0;
            if (b->next[v] >= BEND_CANDIDATES)
                continue;
            int free_ = 1;
            for (uint32_t j = b->vf_first[v]; j < b->vf_first[v + 1] && free_; ++j)
                free_ = !b->taken[b->vf[j]];
            if (!free_)
                continue;
            while (b->next[v] < BEND_CANDIDATES && !vertex_try(b, v))
                ++b->next[v];
            if (b->next[v] >= BEND_CANDIDATES)
                continue;
            for (uint32_t j = b->vf_first[v]; j < b->vf_first[v + 1]; ++j)
                b->taken[b->vf[j]] = 1;
            b->moved[v] = 1;
            ++movers;
        }
        if (!movers)
            return MESO_OK;
        for (;;) {
            uint32_t nb = 0, back = 0;
            meso_result r = meso_shell_checker_bad_faces(b->chk, b->cand, b->bad, &nb, err);
            if (r != MESO_OK)
                return r;
            if (nb == 0)
                break;
            for (uint32_t f = 0; f < nt; ++f)
                for (int k = 0; b->bad[f] && k < 3; ++k) {
                    const uint32_t v = m->indices[3 * (size_t)f + (size_t)k];
                    if (!b->moved[v])
                        continue;
                    memcpy(b->cand + 3 * (size_t)v, b->d + 3 * (size_t)v, 3 * sizeof(float));
                    b->moved[v] = 0;
                    ++b->next[v];
                    ++back;
                }
            if (!back) /* a bad face with no mover: cannot be, d was valid */
                for (uint32_t v = 0; v < nv; ++v)
                    if (b->moved[v]) {
                        memcpy(b->cand + 3 * (size_t)v, b->d + 3 * (size_t)v, 3 * sizeof(float));
                        b->moved[v] = 0;
                        ++b->next[v];
                    }
        }
        for (uint32_t v = 0; v < nv; ++v)
            if (b->moved[v]) {
                b->next[v] = BEND_CANDIDATES;
                b->changed[v] = 1;
            }
        memcpy(b->d, b->cand, sizeof(float) * nd);
    }
}

/* The movers of a pass: the vertices (of redo) whose director is shorter
 * than allowed; their directions from d as it is now. */
static void pass_start(bend* b, const uint8_t* redo)
{
    const meso_mesh* m = b->m;
    for (uint32_t v = 0; v < m->vertex_count; ++v) {
        const float* dv = b->d + 3 * (size_t)v;
        const double l = len3f(dv);
        b->next[v] = BEND_CANDIDATES;
        if ((redo && !redo[v]) || b->vf_first[v] == b->vf_first[v + 1] || !(l < b->allowed[v] * (1.0 - 1e-3)))
            continue;
        b->next[v] = 0;
        double* t = b->dir + 3 * (size_t)v;
        double* rv = b->ring + 3 * (size_t)v;
        for (int i = 0; i < 3; ++i) {
            t[i] = l > 0 ? dv[i] / l : b->sign * (double)b->normals[3 * (size_t)v + i];
            rv[i] = 0.0;
        }
        for (uint32_t j = b->vf_first[v]; j < b->vf_first[v + 1]; ++j)
            for (int k = 0; k < 3; ++k) {
                const uint32_t u = m->indices[3 * (size_t)b->vf[j] + (size_t)k];
                const float* du = b->d + 3 * (size_t)u;
                const double lu = len3f(du);
                for (int i = 0; u != v && lu > 0 && i < 3; ++i)
                    rv[i] += du[i] / lu; /* each neighbour twice in a closed fan: the same mean */
            }
        const double rl = sqrt(rv[0] * rv[0] + rv[1] * rv[1] + rv[2] * rv[2]);
        for (int i = 0; i < 3; ++i)
            rv[i] = rl > 0 ? rv[i] / rl : 0.0; /* unit, so r + s·n is half-way (0: no ring, skipped) */
    }
}

meso_result meso_shell_bend(const meso_mesh* m, float* d, const float* normals, const double* allowed, int sign,
                            int threads, const uint8_t* redo, meso_shell_checker* shared, uint32_t* bent,
                            meso_error* err)
{
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    const size_t n1 = nv ? nv : 1;
    if (bent)
        *bent = 0;
    bend b = {.m = m, .normals = normals, .allowed = allowed, .sign = sign, .d = d};
    b.cand = malloc(sizeof(float) * 3 * n1);
    b.dir = malloc(sizeof(double) * 3 * n1);
    b.ring = malloc(sizeof(double) * 3 * n1);
    b.next = malloc(n1);
    b.moved = calloc(n1, 1);
    b.changed = calloc(n1, 1);
    b.bad = calloc(nt ? nt : 1, 1);
    b.taken = calloc(nt ? nt : 1, 1);
    meso_result r = b.cand && b.dir && b.ring && b.next && b.moved && b.changed && b.bad && b.taken
                        ? meso_vertex_faces(m, &b.vf_first, &b.vf, "bend", err)
                        : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "bend: out of memory");
    b.chk = shared;
    if (r == MESO_OK && !b.chk)
        r = meso_shell_checker_create(m, sign, threads, &b.chk, err);
    uint32_t nbad = 0;
    if (r == MESO_OK)
        r = meso_shell_checker_bad_faces(b.chk, d, b.bad, &nbad, err);
    /* Two passes: the second starts from the directions the first left
     * (a bent neighbour changes the ring's mean and frees a prism). */
    for (int pass = 0; r == MESO_OK && nbad == 0 && pass < BEND_PASSES; ++pass) {
        pass_start(&b, redo);
        r = bend_pass(&b, err);
    }
    uint32_t n = 0;
    for (uint32_t v = 0; r == MESO_OK && v < nv; ++v)
        n += b.changed[v];
    if (bent)
        *bent = n;
    if (!shared)
        meso_shell_checker_destroy(b.chk);
    free(b.cand), free(b.dir), free(b.ring), free(b.vf_first), free(b.vf), free(b.next), free(b.moved);
    free(b.changed), free(b.bad), free(b.taken);
    return r;
}
