/*
 * shell_checker.c — see shell_checker.h.
 *
 * Why: the hybrid and repair rounds each re-ran the whole-mesh exact checks
 * (prism Jacobians, CGAL offset/offset and offset/base intersections) while a
 * round changes only the directors near the faces that failed. On spot
 * subdivided to 106k triangles (bench_shell size) those checks were most of
 * the repair stage and a third of the directors stage.
 *
 * State kept between calls: the directors of the last call, each face's
 * prism verdict, and the intersecting pairs (self: two offset triangles;
 * cross: offset triangle, base triangle). A face is "changed" when one of its
 * corners' directors differs bit for bit. Then the changed faces' prisms are
 * checked again; a self pair is dropped when either face changed, a cross
 * pair when its offset triangle changed (the base never moves), and every
 * pair with a changed offset triangle is searched afresh. Faces with no
 * changed corner keep their verdicts, which is exact: a verdict depends only
 * on the corners it names. When more than half the faces changed the full
 * search is cheaper and is done instead.
 */
#include "shell_checker.h"

#include <stdlib.h>
#include <string.h>

#include "adapters.h"
#include "bake_threads.h"
#include "meso_clock.h"
#include "shell_validate.h"

#ifndef MESO_HAVE_CGAL
#define MESO_HAVE_CGAL 0
#endif

struct meso_shell_checker {
    const meso_mesh* m;
    int sign, threads;
    int primed;             /* 1 after the first call */
    float* prev;            /* 3 nv: the directors of the last call */
    uint8_t* prism;         /* nt: prism verdict != 0 */
    uint8_t *vchanged, *fchanged;
    uint8_t* force;         /* nv or NULL: vertices the next call treats as changed (prime) */
    double *base, *top;     /* 3 nv: base and offset positions, doubles */
    meso_cgal_pairs self, cross;
    double seconds;
};

meso_result meso_shell_checker_create(const meso_mesh* m, int sign, int threads, meso_shell_checker** out,
                                      meso_error* err)
{
    *out = NULL;
    const size_t nv = m->vertex_count ? m->vertex_count : 1, nt = m->triangle_count ? m->triangle_count : 1;
    meso_shell_checker* c = calloc(1, sizeof(*c));
    if (c) {
        c->m = m;
        c->sign = sign;
        c->threads = meso_bake_thread_count(threads);
        c->prev = malloc(sizeof(float) * 3 * nv);
        c->prism = calloc(nt, 1);
        c->vchanged = calloc(nv, 1);
        c->fchanged = calloc(nt, 1);
        c->base = malloc(sizeof(double) * 3 * nv);
        c->top = malloc(sizeof(double) * 3 * nv);
    }
    if (!c || !c->prev || !c->prism || !c->vchanged || !c->fchanged || !c->base || !c->top) {
        meso_shell_checker_destroy(c);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell check: out of memory");
    }
    for (size_t i = 0; i < 3 * (size_t)m->vertex_count; ++i)
        c->base[i] = c->top[i] = m->positions[i];
    *out = c;
    return MESO_OK;
}

void meso_shell_checker_destroy(meso_shell_checker* c)
{
    if (!c)
        return;
    free(c->prev);
    free(c->prism);
    free(c->vchanged);
    free(c->fchanged);
    free(c->force);
    free(c->base);
    free(c->top);
    free(c->self.pairs);
    free(c->cross.pairs);
    free(c);
}

double meso_shell_checker_seconds(const meso_shell_checker* c)
{
    return c->seconds;
}

meso_result meso_shell_checker_prime(meso_shell_checker* c, const float* d, const uint8_t* dirty, meso_error* err)
{
    const meso_mesh* m = c->m;
    const size_t nv = m->vertex_count;
    if (!c->force && !(c->force = calloc(nv ? nv : 1, 1)))
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell check: out of memory");
    memcpy(c->prev, d, sizeof(float) * 3 * nv);
    memcpy(c->force, dirty, nv);
    for (size_t i = 0; i < 3 * nv; ++i)
        c->top[i] = (double)m->positions[i] + (double)d[i];
    memset(c->prism, 0, m->triangle_count ? m->triangle_count : 1);
    c->self.count = c->cross.count = 0;
    c->primed = 1;
    return MESO_OK;
}

/* Drop the pairs of `l` whose first face changed (both: or second), in order. */
static void filter_pairs(meso_cgal_pairs* l, const uint8_t* fchanged, int both)
{
    size_t n = 0;
    for (size_t i = 0; i < l->count; ++i) {
        const uint32_t a = l->pairs[2 * i], b = l->pairs[2 * i + 1];
        if (fchanged[a] || (both && fchanged[b]))
            continue;
        l->pairs[2 * n] = a;
        l->pairs[2 * n + 1] = b;
        ++n;
    }
    l->count = n;
}

/* l += add (add is freed). */
static int append_pairs(meso_cgal_pairs* l, meso_cgal_pairs* add)
{
    uint32_t* p = realloc(l->pairs, sizeof(uint32_t) * 2 * (l->count + add->count + 1));
    if (!p) {
        free(add->pairs);
        return 0;
    }
    memcpy(p + 2 * l->count, add->pairs, sizeof(uint32_t) * 2 * add->count);
    l->pairs = p;
    l->count += add->count;
    free(add->pairs);
    memset(add, 0, sizeof(*add));
    return 1;
}

meso_result meso_shell_checker_bad_faces(meso_shell_checker* c, const float* d, uint8_t* bad, uint32_t* count,
                                         meso_error* err)
{
    const double t0 = meso_seconds();
    const meso_mesh* m = c->m;
    const uint32_t nv = m->vertex_count, nt = m->triangle_count;
    /* Changed vertices and faces (all on the first call). */
    uint32_t nchanged = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        c->vchanged[v] = !c->primed || (c->force && c->force[v]) ||
                         memcmp(c->prev + 3 * (size_t)v, d + 3 * (size_t)v, 3 * sizeof(float)) != 0;
        if (c->vchanged[v])
            for (int k = 0; k < 3; ++k)
                c->top[3 * (size_t)v + k] = (double)m->positions[3 * (size_t)v + k] + (double)d[3 * (size_t)v + k];
    }
    for (uint32_t f = 0; f < nt; ++f) {
        const uint32_t* ix = m->indices + 3 * (size_t)f;
        c->fchanged[f] = c->vchanged[ix[0]] | c->vchanged[ix[1]] | c->vchanged[ix[2]];
        nchanged += c->fchanged[f];
    }
    const int full = !c->primed || nchanged > nt / 2;
    memcpy(c->prev, d, sizeof(float) * 3 * (size_t)nv);
    c->primed = 1;
    if (c->force)
        memset(c->force, 0, nv);
    /* Prisms of the changed faces: each verdict depends only on its face. */
    const long ntl = (long)nt;
#ifdef _OPENMP
#pragma omp parallel for schedule(static, 1024) num_threads(c->threads)
#endif
    for (long f = 0; f < ntl; ++f) {
        if (!c->fchanged[f])
            continue;
        double b[9], dd[9];
        for (int i = 0; i < 3; ++i) {
            const uint32_t v = m->indices[3 * (size_t)f + (size_t)i];
            for (int k = 0; k < 3; ++k) {
                b[3 * i + k] = m->positions[3 * (size_t)v + k];
                dd[3 * i + k] = d[3 * (size_t)v + k];
            }
        }
        c->prism[f] = meso_shell_prism_check(b, dd, c->sign) != 0;
    }
    meso_result r = MESO_OK;
#if MESO_HAVE_CGAL
    if (nchanged) {
        meso_cgal_pairs self, cross;
        r = meso_cgal_shell_pairs(c->top, c->base, nv, m->indices, nt, full ? NULL : c->fchanged, c->threads, &self,
                                  &cross, err);
        if (r == MESO_OK && full) {
            free(c->self.pairs);
            free(c->cross.pairs);
            c->self = self;
            c->cross = cross;
        } else if (r == MESO_OK) {
            filter_pairs(&c->self, c->fchanged, 1);
            filter_pairs(&c->cross, c->fchanged, 0);
            const int ok_self = append_pairs(&c->self, &self);
            const int ok_cross = append_pairs(&c->cross, &cross);
            if (!ok_self || !ok_cross)
                r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell check: out of memory");
        }
    }
#endif
    uint32_t n = 0;
    if (r == MESO_OK) {
        memcpy(bad, c->prism, nt);
        for (size_t i = 0; i < 2 * c->self.count; ++i)
            bad[c->self.pairs[i]] = 1;
        for (size_t i = 0; i < 2 * c->cross.count; ++i)
            bad[c->cross.pairs[i]] = 1;
        for (uint32_t f = 0; f < nt; ++f)
            n += bad[f];
        *count = n;
    } else {
        c->primed = 0; /* the pair lists are not current: check everything next time */
    }
    c->seconds += meso_seconds() - t0;
    return r;
}
