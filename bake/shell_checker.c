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
#include "box_grid.h"
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
    /* Broad phase of the incremental calls (built at the first one): the
     * offset and base triangles' boxes. */
    meso_box_grid *gtop, *gbase;
    double cell;     /* the grids' cell edge, once chosen */
    uint32_t* found; /* one query's items */
    size_t found_n, found_cap;
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
    meso_box_grid_destroy(c->gtop);
    meso_box_grid_destroy(c->gbase);
    free(c->found);
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

/* The box of triangle f over positions xyz. */
static void tri_box(const double* xyz, const uint32_t* ix, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; ++k) {
        lo[k] = hi[k] = xyz[3 * (size_t)ix[0] + k];
        for (int i = 1; i < 3; ++i) {
            const double x = xyz[3 * (size_t)ix[i] + k];
            lo[k] = x < lo[k] ? x : lo[k];
            hi[k] = x > hi[k] ? x : hi[k];
        }
    }
}

/* A grid of the triangles' boxes over positions xyz; NULL when out of
 * memory. */
static meso_box_grid* grid_of(const meso_mesh* m, const double* xyz, double cell)
{
    const uint32_t nt = m->triangle_count;
    meso_box_grid* g = meso_box_grid_create(nt, cell);
    for (uint32_t f = 0; g && f < nt; ++f) {
        double lo[3], hi[3];
        tri_box(xyz, m->indices + 3 * (size_t)f, lo, hi);
        if (!meso_box_grid_set(g, f, lo, hi)) {
            meso_box_grid_destroy(g);
            g = NULL;
        }
    }
    return g;
}

/* Both grids, current for the offset positions in c->top: the changed
 * faces re-set, or the offset grid built anew after a full search (which
 * leaves it stale; the base grid never is: the base does not move). Cells:
 * the mean largest extent of the offset triangles' boxes when the offset
 * grid is first built. Two grids to build are built on two threads. */
static int grids_update(meso_shell_checker* c)
{
    const meso_mesh* m = c->m;
    const uint32_t nt = m->triangle_count;
    double lo[3], hi[3];
    if (!c->gtop) {
        if (!(c->cell > 0)) {
            double sum = 0;
            for (uint32_t f = 0; f < nt; ++f) {
                tri_box(c->top, m->indices + 3 * (size_t)f, lo, hi);
                double e = 0;
                for (int k = 0; k < 3; ++k)
                    e = hi[k] - lo[k] > e ? hi[k] - lo[k] : e;
                sum += e;
            }
            c->cell = nt && sum > 0 ? sum / nt : 1.0;
        }
        const int both = !c->gbase;
#ifdef _OPENMP
#pragma omp parallel sections num_threads(both && c->threads > 1 ? 2 : 1)
#endif
        {
#ifdef _OPENMP
#pragma omp section
#endif
            c->gtop = grid_of(m, c->top, c->cell);
#ifdef _OPENMP
#pragma omp section
#endif
            if (both)
                c->gbase = grid_of(m, c->base, c->cell);
        }
        return c->gtop && c->gbase;
    }
    for (uint32_t f = 0; f < nt; ++f)
        if (c->fchanged[f]) {
            tri_box(c->top, m->indices + 3 * (size_t)f, lo, hi);
            if (!meso_box_grid_set(c->gtop, f, lo, hi))
                return 0;
        }
    return 1;
}

/* l = the pairs of cand (2 n) whose exact test hit. */
static int keep_hits(const uint32_t* cand, size_t n, const uint8_t* hit, meso_cgal_pairs* l)
{
    size_t k = 0;
    for (size_t i = 0; i < n; ++i)
        k += hit[i];
    l->pairs = malloc(sizeof(uint32_t) * 2 * (k ? k : 1));
    l->count = 0;
    if (!l->pairs)
        return 0;
    for (size_t i = 0; i < n; ++i)
        if (hit[i]) {
            l->pairs[2 * l->count] = cand[2 * i];
            l->pairs[2 * l->count + 1] = cand[2 * i + 1];
            l->count++;
        }
    return 1;
}

/* meso_cgal_shell_pairs(..., changed = c->fchanged, ...) with the grids as
 * the broad phase: the changed offset triangles' boxes against every offset
 * box (a pair of two changed ones once, the smaller index first) and every
 * base box, then the same exact test. O(changed faces x their neighbours)
 * instead of O(all faces) per call. */
static meso_result changed_pairs(meso_shell_checker* c, meso_cgal_pairs* self, meso_cgal_pairs* cross,
                                 meso_error* err)
{
    const meso_mesh* m = c->m;
    const uint32_t nt = m->triangle_count;
    memset(self, 0, sizeof(*self));
    memset(cross, 0, sizeof(*cross));
    if (!grids_update(c))
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell check: out of memory");
    uint32_t *cs = NULL, *cx = NULL;
    size_t ns = 0, nx = 0, caps = 0, capx = 0;
    int ok = 1;
    for (uint32_t f = 0; f < nt && ok; ++f) {
        if (!c->fchanged[f])
            continue;
        double lo[3], hi[3];
        tri_box(c->top, m->indices + 3 * (size_t)f, lo, hi);
        for (int set = 0; set < 2 && ok; ++set) {
            c->found_n = 0;
            ok = meso_box_grid_query(set ? c->gbase : c->gtop, lo, hi, &c->found, &c->found_n, &c->found_cap);
            uint32_t** l = set ? &cx : &cs;
            size_t* n = set ? &nx : &ns;
            size_t* cap = set ? &capx : &caps;
            for (size_t i = 0; i < c->found_n && ok; ++i) {
                const uint32_t g = c->found[i];
                if (!set && (g == f || (c->fchanged[g] && g < f)))
                    continue;
                if (*n == *cap) {
                    const size_t cc = *cap ? 2 * *cap : 1024;
                    uint32_t* p = realloc(*l, sizeof(uint32_t) * 2 * cc);
                    if (!p) {
                        ok = 0;
                        break;
                    }
                    *l = p;
                    *cap = cc;
                }
                (*l)[2 * *n] = f;
                (*l)[2 * *n + 1] = g;
                ++*n;
            }
        }
    }
    uint8_t* hit = ok ? malloc((ns > nx ? ns : nx) + 1) : NULL;
    meso_result r = hit ? MESO_OK : meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell check: out of memory");
    if (r == MESO_OK)
        r = meso_cgal_test_pairs(c->top, c->base, m->vertex_count, m->indices, nt, cs, ns, 0, c->threads, hit, err);
    if (r == MESO_OK && !keep_hits(cs, ns, hit, self))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell check: out of memory");
    if (r == MESO_OK)
        r = meso_cgal_test_pairs(c->top, c->base, m->vertex_count, m->indices, nt, cx, nx, 1, c->threads, hit, err);
    if (r == MESO_OK && !keep_hits(cx, nx, hit, cross))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "shell check: out of memory");
    if (r != MESO_OK) {
        free(self->pairs);
        free(cross->pairs);
        memset(self, 0, sizeof(*self));
        memset(cross, 0, sizeof(*cross));
    }
    free(cs), free(cx), free(hit);
    return r;
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
#pragma omp parallel for schedule(static, 1024) num_threads(c->threads) if (nchanged > 4096)
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
        if (full) {
            r = meso_cgal_shell_pairs(c->top, c->base, nv, m->indices, nt, NULL, c->threads, &self, &cross, err);
            /* the offset grid (if any) is stale everywhere: rebuilt at the next incremental call */
            meso_box_grid_destroy(c->gtop);
            c->gtop = NULL;
        } else {
            r = changed_pairs(c, &self, &cross, err);
        }
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
