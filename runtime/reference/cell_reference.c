/*
 * cell_reference.c — the exact CPU reference for cell-based objects
 * (cell_reference.h; cell-based-object-representation.md §3.2).
 *
 * The traversal is written as the merge of the three per-axis sequences of
 * grid-plane crossings, ordered by (s, axis): the voxel walk takes the
 * smallest next crossing, and a jump (a skipped tile, the way into the grid
 * box) finds, per axis, the last crossing ordered before the event it jumps
 * to (index_after). Both compute every crossing's s with the same
 * expression (plane_s), so a jump lands on exactly the state the walk
 * reaches, ties included.
 *
 * Sections: >>membership (MEMB decoded on the fly, the dense-tag encoder),
 * >>files (meso_ref_cells_load), >>traversal, >>shading, >>paths (first hit,
 * reflection, refraction), >>render (rows on pthreads, as
 * frustum_reference.c).
 */
#include "cell_reference.h"

#include "meso_layout.h"
#include "ref_common.h"
#include "vec3d.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int meso_ref_cells_skipping = 1;

static uint32_t ld32(const uint8_t* p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

static float ldf32(const uint8_t* p)
{
    const uint32_t u = ld32(p);
    float f;
    memcpy(&f, &u, sizeof(f));
    return f;
}

static uint64_t tile_count(const meso_ref_cells* c)
{
    return (uint64_t)c->tiles[0] * c->tiles[1] * c->tiles[2];
}

/* >>membership ------------------------------------------------------------- */

unsigned meso_ref_cells_class(const meso_ref_cells* c, uint64_t t)
{
    return (c->memb[t / 16] >> (2 * (t % 16))) & 3u;
}

unsigned meso_ref_cells_tag(const meso_ref_cells* c, uint64_t t, uint32_t s)
{
    const uint64_t cw = (tile_count(c) + 15) / 16;
    const uint32_t word = c->memb[t / 16];
    const unsigned cls = (word >> (2 * (t % 16))) & 3u;
    if (cls != 2)
        return cls; /* OUTSIDE or INSIDE: every tag the class */
    uint64_t rec = c->memb[cw + t / 16];
    for (unsigned k = 0; k < t % 16; ++k)
        rec += ((word >> (2 * k)) & 3u) == 2;
    const uint64_t W = (2 * (uint64_t)c->split_count + 31) / 32;
    return (c->memb[2 * cw + rec * W + (s - 1) / 16] >> (2 * ((s - 1) % 16))) & 3u;
}

meso_result meso_ref_cells_set_tags(meso_ref_cells* c, const uint8_t* tags)
{
    if (!c || !tags || !c->tile || c->res == 0 || c->split_count == 0)
        return MESO_ERR_INVALID_ARG;
    const uint64_t T = tile_count(c), S = c->split_count, cw = (T + 15) / 16, W = (2 * S + 31) / 32;
    uint64_t M = 0;
    for (uint64_t t = 0; t < T; ++t) {
        int all_out = 1, all_in = 1;
        for (uint64_t s = 0; s < S; ++s) {
            const uint8_t g = tags[t * S + s];
            if (g > 2)
                return MESO_ERR_INVALID_ARG;
            all_out &= g == 0;
            all_in &= g == 1;
        }
        M += !all_out && !all_in;
    }
    const uint64_t L = 2 * cw + M * W;
    uint32_t* w = calloc((size_t)L, sizeof(*w));
    if (!w)
        return MESO_ERR_OUT_OF_MEMORY;
    uint64_t rec = 0;
    for (uint64_t t = 0; t < T; ++t) {
        if (t % 16 == 0)
            w[cw + t / 16] = (uint32_t)rec;
        int all_out = 1, all_in = 1;
        for (uint64_t s = 0; s < S; ++s) {
            all_out &= tags[t * S + s] == 0;
            all_in &= tags[t * S + s] == 1;
        }
        const uint32_t cls = all_out ? 0u : all_in ? 1u : 2u;
        w[t / 16] |= cls << (2 * (t % 16));
        if (cls != 2)
            continue;
        for (uint64_t s = 0; s < S; ++s)
            w[2 * cw + rec * W + s / 16] |= (uint32_t)tags[t * S + s] << (2 * (s % 16));
        ++rec;
    }
    free(c->memb);
    c->memb = w;
    c->memb_words = L;
    const size_t n = (size_t)c->res * c->res * c->res;
    c->map_full = 1;
    for (size_t v = 0; v < n; ++v)
        c->map_full &= c->tile[v] != 0;
    return MESO_OK;
}

/* >>files ------------------------------------------------------------------ */

/* The chunk of `type` level `lod` draws (FORMAT.md §7.10), read whole
 * (meso_file_check_cells_level has checked that it exists with the element
 * and dims CELL implies). */
static meso_result read_chunk(meso_file* f, uint32_t id, uint16_t lod, uint32_t type, void** out, meso_error* err)
{
    size_t size = 0;
    return mesoi_ref_read_whole(f, meso_file_find_level(f, type, id, lod), out, &size, err);
}

/* FORMAT.md 7.2 "Normals": octahedral U16 x 2 to a unit vector. */
static void octa_decode(uint16_t u0, uint16_t u1, float out[3])
{
    const double f0 = u0 / 65535.0 * 2 - 1, f1 = u1 / 65535.0 * 2 - 1;
    double n[3] = {f0, f1, 1 - fabs(f0) - fabs(f1)};
    if (n[2] < 0) {
        n[0] = (1 - fabs(f1)) * (f0 >= 0 ? 1 : -1);
        n[1] = (1 - fabs(f0)) * (f1 >= 0 ? 1 : -1);
    }
    normalize3(n);
    for (int k = 0; k < 3; ++k)
        out[k] = (float)n[k];
}

static double srgb_to_linear(double x);

/* The optional TX3D colour grid (U8 x 4; meso_file_check_object's 6301
 * holds it to that, refused here too). */
static meso_result load_grid(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_cells* out, meso_error* err)
{
    const int32_t gi = meso_file_find_level(f, MESO_CHUNK_TX3D, object_id, lod);
    if (gi < 0)
        return MESO_OK;
    const meso_chunk_info* k = meso_file_chunk(f, (uint32_t)gi);
    if (k->dtype != MESO_DTYPE_U8 || k->components != 4 || !k->dims[0] || !k->dims[1] || !k->dims[2])
        return mesoi_ref_fail(err, MESO_ERR_CORRUPT, "cells", object_id, "TX3D colour grid is not U8 x 4");
    void* raw = NULL;
    size_t size = 0;
    meso_result r = mesoi_ref_read_whole(f, gi, &raw, &size, err);
    if (r != MESO_OK)
        return r;
    const size_t n = (size_t)k->dims[0] * k->dims[1] * k->dims[2];
    out->grid_rgb = size == 4 * n ? malloc(sizeof(double) * 3 * n) : NULL;
    if (!out->grid_rgb) {
        free(raw);
        return mesoi_ref_fail(err, MESO_ERR_OUT_OF_MEMORY, "cells", object_id, "colour grid: out of memory");
    }
    for (size_t i = 0; i < 3 * n; ++i)
        out->grid_rgb[i] = srgb_to_linear(((const uint8_t*)raw)[4 * (i / 3) + i % 3] / 255.0);
    free(raw);
    memcpy(out->grid, k->dims, sizeof(out->grid));
    return MESO_OK;
}

meso_result meso_ref_cells_load(meso_file* f, uint32_t object_id, meso_ref_cells* out, meso_error* err)
{
    return meso_ref_cells_load_level(f, object_id, 0, out, err);
}

meso_result meso_ref_cells_load_level(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_cells* out,
                                      meso_error* err)
{
    if (!f || !out)
        return mesoi_ref_fail(err, MESO_ERR_INVALID_ARG, "cells", object_id, "NULL file or output");
    memset(out, 0, sizeof(*out));
    meso_object_record rec;
    meso_result r = mesoi_ref_object(f, object_id, MESO_OBJECT_CELLS, "cells", &rec, err);
    if (r != MESO_OK)
        return r;
    /* Every chunk against CELL (FORMAT.md 7.8: 4801-4806), as mesoinspect
     * validate --full checks it: what follows may trust sizes and ids. */
    if ((r = meso_file_check_cells_level(f, object_id, lod, err)) != MESO_OK)
        return r;
    void *cell = NULL, *tile = NULL, *memb = NULL, *nrmm = NULL, *colr = NULL;
    if ((r = read_chunk(f, object_id, lod, MESO_CHUNK_CELL, &cell, err)) != MESO_OK)
        goto done;
    const uint8_t* cr = cell;
    for (int a = 0; a < 3; ++a) {
        out->tiles[a] = ld32(cr + MESO_CELL_OFF_TILES + 4 * a);
        out->origin[a] = ldf32(cr + MESO_CELL_OFF_ORIGIN + 4 * a);
    }
    out->res = ld32(cr + MESO_CELL_OFF_TILE_RES);
    out->split_count = ld32(cr + MESO_CELL_OFF_SPLIT_COUNT);
    out->cell_count = ld32(cr + MESO_CELL_OFF_CELL_COUNT);
    out->voxel = ldf32(cr + MESO_CELL_OFF_VOXEL_SIZE);
    const uint32_t R = out->res;
    if ((r = read_chunk(f, object_id, lod, MESO_CHUNK_TILE, &tile, err)) != MESO_OK ||
        (r = read_chunk(f, object_id, lod, MESO_CHUNK_MEMB, &memb, err)) != MESO_OK ||
        (r = read_chunk(f, object_id, lod, MESO_CHUNK_NRMM, &nrmm, err)) != MESO_OK ||
        (r = read_chunk(f, object_id, lod, MESO_CHUNK_COLR, &colr, err)) != MESO_OK)
        goto done;
    const size_t n = (size_t)R * R * R;
    const uint64_t L = meso_file_chunk(f, (uint32_t)meso_file_find_level(f, MESO_CHUNK_MEMB, object_id, lod))->dims[0];
    const int tile_u32 = meso_file_chunk(f, (uint32_t)meso_file_find_level(f, MESO_CHUNK_TILE, object_id, lod))->dtype ==
                         MESO_DTYPE_U32;
    out->tile = malloc(sizeof(*out->tile) * n);
    out->memb = malloc(sizeof(*out->memb) * (size_t)L);
    out->normal = malloc(sizeof(*out->normal) * 3 * n);
    out->colour = malloc(4 * n);
    if (!out->tile || !out->memb || !out->normal || !out->colour) {
        r = mesoi_ref_fail(err, MESO_ERR_OUT_OF_MEMORY, "cells", object_id, "out of memory");
        goto done;
    }
    out->memb_words = L;
    out->map_full = 1;
    for (size_t v = 0; v < n; ++v) {
        const uint8_t* b = (const uint8_t*)tile + (tile_u32 ? 4 : 2) * v;
        out->tile[v] = tile_u32 ? ld32(b) : (uint32_t)(b[0] | b[1] << 8);
        out->map_full &= out->tile[v] != 0;
        const uint8_t* q = (const uint8_t*)nrmm + 4 * v;
        octa_decode((uint16_t)(q[0] | q[1] << 8), (uint16_t)(q[2] | q[3] << 8), &out->normal[3 * v]);
    }
    for (uint64_t k = 0; k < L; ++k)
        out->memb[k] = ld32((const uint8_t*)memb + 4 * k);
    memcpy(out->colour, colr, 4 * n);
    if ((r = load_grid(f, object_id, lod, out, err)) != MESO_OK)
        goto done;
done:
    free(cell);
    free(tile);
    free(memb);
    free(nrmm);
    free(colr);
    if (r != MESO_OK)
        meso_ref_cells_free(out);
    return r;
}

void meso_ref_cells_free(meso_ref_cells* c)
{
    if (!c)
        return;
    free(c->tile);
    free(c->memb);
    free(c->normal);
    free(c->colour);
    free(c->grid_rgb);
    memset(c, 0, sizeof(*c));
}

/* >>traversal -------------------------------------------------------------- */

static int in_grid(const meso_ref_cells* c, const int64_t v[3])
{
    for (int a = 0; a < 3; ++a)
        if (v[a] < 0 || v[a] >= (int64_t)c->tiles[a] * c->res)
            return 0;
    return 1;
}

static size_t map_index(const meso_ref_cells* c, const int64_t v[3])
{
    const int64_t R = c->res;
    return (size_t)(v[0] % R + R * (v[1] % R + R * (v[2] % R)));
}

static uint64_t tile_of(const meso_ref_cells* c, const int64_t v[3])
{
    const uint64_t R = c->res;
    return (uint64_t)v[0] / R + c->tiles[0] * ((uint64_t)v[1] / R + (uint64_t)c->tiles[1] * ((uint64_t)v[2] / R));
}

int meso_ref_cells_solid(const meso_ref_cells* c, int64_t i, int64_t j, int64_t k)
{
    const int64_t v[3] = {i, j, k};
    if (!in_grid(c, v))
        return 0;
    const uint32_t s = c->tile[map_index(c, v)];
    return s != 0 && meso_ref_cells_tag(c, tile_of(c, v), s) == 1;
}

typedef struct walk {
    const meso_ref_cells* c;
    double o[3], u[3];
} walk;

/* s where the ray crosses grid plane x (integer grid coordinate) of axis a. */
static double plane_s(const walk* w, int a, int64_t x)
{
    return (w->c->origin[a] + (double)x * w->c->voxel - w->o[a]) / w->u[a];
}

/* (s1, a1) ordered before (s2, a2), or equal to it when incl. */
static int ordered(double s1, int a1, double s2, int a2, int incl)
{
    return s1 < s2 || (s1 == s2 && (a1 < a2 || (a1 == a2 && incl)));
}

/* The voxel index along axis b after every b-crossing ordered before the
 * event (S, A) (or at it, incl), starting from index cur (never behind). */
static int64_t index_after(const walk* w, int b, int64_t cur, double S, int A, int incl)
{
    if (w->u[b] == 0)
        return cur;
    const double gd = floor((w->o[b] + S * w->u[b] - w->c->origin[b]) / w->c->voxel);
    const double lim = 4e15;
    if (w->u[b] > 0) { /* in voxel g: plane g crossed (g > cur), plane g + 1 not */
        int64_t g = !(gd > (double)cur) ? cur : gd > lim ? (int64_t)lim : (int64_t)gd;
        while (ordered(plane_s(w, b, g + 1), b, S, A, incl))
            ++g;
        while (g > cur && !ordered(plane_s(w, b, g), b, S, A, incl))
            --g;
        return g;
    }
    int64_t g = !(gd < (double)cur) ? cur : gd < -lim ? (int64_t)-lim : (int64_t)gd;
    while (ordered(plane_s(w, b, g), b, S, A, incl)) /* in voxel g: plane g + 1 crossed (g < cur), plane g not */
        --g;
    while (g < cur && !ordered(plane_s(w, b, g + 1), b, S, A, incl))
        ++g;
    return g;
}

/* Jump to the state just after event (S, A): cur and prev (the state
 * before it). */
static void jump(const walk* w, int64_t cur[3], int64_t prev[3], double S, int A)
{
    for (int b = 0; b < 3; ++b) {
        prev[b] = index_after(w, b, cur[b], S, A, 0);
        cur[b] = index_after(w, b, cur[b], S, A, 1);
    }
}

int meso_ref_cells_search(const meso_ref_cells* c, const double o[3], const double u[3], const int64_t start[3],
                          double s_max, int want_solid, double* s, int64_t voxel[3], int64_t last[3], int* axis,
                          uint64_t* steps)
{
    walk w = {c, {o[0], o[1], o[2]}, {u[0], u[1], u[2]}};
    int64_t cur[3] = {start[0], start[1], start[2]}, prev[3] = {start[0], start[1], start[2]};
    double s_cur = 0;
    int ax = -1;
    want_solid = want_solid != 0;
    for (int a = 0; a < 3; ++a) /* beyond 2^40 voxels away the crossings' s lose their order: refused */
        if (!isfinite(u[a]) || !(fabs(o[a] - c->origin[a]) < 1099511627776.0 * c->voxel) || !(c->voxel > 0))
            return 0;
    if (steps)
        ++*steps;
    if (!(in_grid(c, cur) ? meso_ref_cells_solid(c, cur[0], cur[1], cur[2]) == want_solid : !want_solid)) {
        if (!in_grid(c, cur)) { /* looking for solid from beyond the grid: jump to the grid box's entry */
            double S = -HUGE_VAL;
            int A = -1;
            for (int b = 0; b < 3; ++b) {
                const int64_t N = (int64_t)c->tiles[b] * c->res;
                if (cur[b] >= 0 && cur[b] < N)
                    continue;
                if (cur[b] < 0 ? !(u[b] > 0) : !(u[b] < 0))
                    return 0; /* never enters along b */
                const double sb = plane_s(&w, b, cur[b] < 0 ? 0 : N);
                if (A < 0 || ordered(S, A, sb, b, 0)) {
                    S = sb;
                    A = b;
                }
            }
            if (!(S <= s_max) || !isfinite(S))
                return 0;
            jump(&w, cur, prev, S, A);
            if (!in_grid(c, cur))
                return 0; /* the ray passes by the box */
            s_cur = S;
            ax = A;
            if (steps)
                ++*steps;
        }
        while (!(in_grid(c, cur) && meso_ref_cells_solid(c, cur[0], cur[1], cur[2]) == want_solid)) {
            if (!in_grid(c, cur)) {
                if (want_solid)
                    return 0; /* left the grid box (convex: for good) */
                break;        /* beyond the grid is empty */
            }
            const uint64_t t = tile_of(c, cur);
            const unsigned cls = meso_ref_cells_class(c, t);
            double S = HUGE_VAL;
            int A = -1;
            if (meso_ref_cells_skipping && (want_solid ? cls == 0 : cls == 1 && c->map_full)) {
                for (int b = 0; b < 3; ++b) { /* the first crossing that leaves the tile */
                    if (u[b] == 0)
                        continue;
                    const int64_t t0 = cur[b] / c->res * c->res;
                    const double sb = plane_s(&w, b, u[b] > 0 ? t0 + c->res : t0);
                    if (A < 0 || ordered(sb, b, S, A, 0)) {
                        S = sb;
                        A = b;
                    }
                }
                if (A < 0 || !(S <= s_max) || !isfinite(S))
                    return 0;
                jump(&w, cur, prev, S, A);
            } else {
                for (int b = 0; b < 3; ++b) { /* the next crossing */
                    if (u[b] == 0)
                        continue;
                    const double sb = plane_s(&w, b, u[b] > 0 ? cur[b] + 1 : cur[b]);
                    if (A < 0 || ordered(sb, b, S, A, 0)) {
                        S = sb;
                        A = b;
                    }
                }
                if (A < 0 || !(S <= s_max) || !isfinite(S))
                    return 0;
                memcpy(prev, cur, sizeof(prev));
                cur[A] += u[A] > 0 ? 1 : -1;
            }
            s_cur = S;
            ax = A;
            if (steps)
                ++*steps;
        }
    }
    *s = s_cur;
    if (axis)
        *axis = ax;
    if (voxel)
        memcpy(voxel, cur, sizeof(cur));
    if (last)
        memcpy(last, prev, sizeof(prev));
    return 1;
}

/* >>shading ---------------------------------------------------------------- */

static double srgb_to_linear(double x)
{
    return x <= 0.04045 ? x / 12.92 : pow((x + 0.055) / 1.055, 2.4);
}

void meso_ref_cells_env(const double u[3], double rgb[3])
{
    const double cy = fmax(u[1], 0.0), g = fmax(-u[1], 0.0);
    const double top[3] = {0.95, 0.92, 0.85}, zen[3] = {0.30, 0.50, 0.90};
    const double stripe = 0.12 * sin(12 * atan2(u[2], u[0])) * sin(12 * asin(fmin(g, 1.0)));
    const double wg = fmin(1.0, 8 * g);
    for (int k = 0; k < 3; ++k) {
        const double sky = top[k] * (1 - cy) + zen[k] * cy;
        const double ground = (k == 0 ? 0.42 : k == 1 ? 0.36 : 0.30) + stripe;
        rgb[k] = u[1] >= 0 ? sky : sky * (1 - wg) + ground * wg;
    }
}

/* NRMM normal of SOLID voxel v. */
static void map_normal(const meso_ref_cells* c, const int64_t v[3], double m[3])
{
    const float* p = &c->normal[3 * map_index(c, v)];
    for (int k = 0; k < 3; ++k)
        m[k] = p[k];
}

/* n = m if m . f > 0, else f. */
static void pick_normal(const meso_ref_cells* c, const int64_t v[3], const double f[3], double n[3])
{
    double m[3];
    map_normal(c, v, m);
    const int use_m = dot3(m, f) > 0;
    for (int k = 0; k < 3; ++k)
        n[k] = use_m ? m[k] : f[k];
}

void meso_ref_cells_albedo(const meso_ref_cells* c, const int64_t v[3], const double p[3], double rgb[3])
{
    if (!c->grid[0]) {
        const uint8_t* col = &c->colour[4 * map_index(c, v)];
        for (int i = 0; i < 3; ++i)
            rgb[i] = srgb_to_linear(col[i] / 255.0);
        return;
    }
    uint32_t i0[3], i1[3];
    double f[3];
    for (int a = 0; a < 3; ++a) {
        const double ext = (double)c->tiles[a] * c->res * c->voxel;
        const double x = fmin(fmax((p[a] - c->origin[a]) / ext * c->grid[a] - 0.5, 0.0), c->grid[a] - 1.0);
        i0[a] = (uint32_t)x;
        i1[a] = i0[a] + 1 < c->grid[a] ? i0[a] + 1 : i0[a];
        f[a] = x - i0[a];
    }
    for (int k = 0; k < 3; ++k) {
        double acc = 0;
        for (int corner = 0; corner < 8; ++corner) {
            const uint32_t ix = corner & 1 ? i1[0] : i0[0], iy = corner & 2 ? i1[1] : i0[1],
                           iz = corner & 4 ? i1[2] : i0[2];
            const double w = (corner & 1 ? f[0] : 1 - f[0]) * (corner & 2 ? f[1] : 1 - f[1]) *
                             (corner & 4 ? f[2] : 1 - f[2]);
            acc += w * c->grid_rgb[3 * (((size_t)iz * c->grid[1] + iy) * c->grid[0] + ix) + (size_t)k];
        }
        rgb[k] = acc;
    }
}

static void shade(const meso_ref_cells* c, const int64_t v[3], const double p[3], const double n[3],
                  const double l[3], double rgb[3])
{
    const double k = 0.15 + 0.85 * fmax(0.0, dot3(n, l));
    meso_ref_cells_albedo(c, v, p, rgb);
    for (int i = 0; i < 3; ++i)
        rgb[i] *= k;
}

static void reflect(const double u[3], const double n[3], double r[3])
{
    const double d = dot3(u, n);
    for (int k = 0; k < 3; ++k)
        r[k] = u[k] - 2 * d * n[k];
    normalize3(r);
}

/* GLSL refract (n faces the ray); 0 on total internal reflection. */
static int refract(const double u[3], const double n[3], double eta, double t[3])
{
    const double d = dot3(n, u), k = 1 - eta * eta * (1 - d * d);
    if (k < 0)
        return 0;
    for (int i = 0; i < 3; ++i)
        t[i] = eta * u[i] - (eta * d + sqrt(k)) * n[i];
    normalize3(t);
    return 1;
}

/* One interface event for refraction: ray d meets a face whose normal g
 * faces the ray (g . d < 0), shading normal ns (facing the ray too).
 * Refraction must cross (g . t < 0), a total internal reflection stay
 * (g . r > 0); otherwise the event is recomputed with g. Returns 1 when the
 * ray crossed the face. */
static int interface(const double d[3], const double ns[3], const double g[3], double eta, double out[3])
{
    if (refract(d, ns, eta, out)) {
        if (dot3(g, out) < 0)
            return 1;
    } else {
        reflect(d, ns, out);
        if (dot3(g, out) > 0)
            return 0;
    }
    if (refract(d, g, eta, out))
        return 1;
    reflect(d, g, out);
    return 0;
}

/* >>paths ------------------------------------------------------------------ */

static void environment(const meso_ref_cells_opts* op, const double u[3], double rgb[3])
{
    if (op->env)
        op->env(u, rgb, op->env_user);
    else
        meso_ref_cells_env(u, rgb);
}

static void face(int axis, const double u[3], double sign, double f[3])
{
    f[0] = f[1] = f[2] = 0;
    f[axis] = sign * (u[axis] > 0 ? 1 : -1);
}

/* Event b (1..8) of a path. */
static void record(meso_ref_cells_path* out, int b, const double p[3], const double n[3], const int64_t v[3],
                   const double d[3])
{
    if (b < 1 || b > 8)
        return;
    out->events = b;
    for (int k = 0; k < 3; ++k) {
        out->p[b][k] = p[k];
        out->n[b][k] = n[k];
        out->voxel[b][k] = v[k];
        out->dir[b][k] = d[k];
    }
}

static void advance(const double o[3], const double u[3], double s, double p[3])
{
    for (int k = 0; k < 3; ++k)
        p[k] = o[k] + s * u[k];
}

void meso_ref_cells_trace(const meso_ref_cells* c, const double o[3], const double u[3], double s_max,
                          const double light[3], const meso_ref_cells_opts* opts, meso_ref_cells_path* out)
{
    memset(out, 0, sizeof(*out));
    const meso_ref_cells_opts def = {.mode = MESO_REF_CELLS_FIRST_HIT};
    const meso_ref_cells_opts* op = opts ? opts : &def;
    const int B = op->bounces < 0 ? 0 : op->bounces > 8 ? 8 : op->bounces;
    const double kr = op->reflectivity != 0 ? op->reflectivity : 0.5;
    const double ior = op->ior != 0 ? op->ior : 1.5;
    const double tau = op->transparency != 0 ? op->transparency : 0.7;
    int64_t start[3];
    for (int a = 0; a < 3; ++a)
        if (!(fabs(o[a] - c->origin[a]) < 1099511627776.0 * c->voxel) || !isfinite(u[a]))
            return; /* as meso_ref_cells_search: no hit */
    for (int a = 0; a < 3; ++a) { /* the voxel whose [x, x + 1) h box holds o, in plane_s's arithmetic */
        const walk w = {c, {o[0], o[1], o[2]}, {1, 1, 1}};
        const double gd = floor((o[a] - c->origin[a]) / c->voxel);
        int64_t x = gd > 4e15 ? (int64_t)4e15 : gd < -4e15 ? (int64_t)-4e15 : (int64_t)gd;
        while (plane_s(&w, a, x) > 0)
            --x;
        while (plane_s(&w, a, x + 1) <= 0)
            ++x;
        start[a] = x;
    }
    double s0;
    int64_t v[3], last[3];
    int axis;
    if (!meso_ref_cells_search(c, o, u, start, s_max, 1, &s0, v, last, &axis, NULL))
        return;
    out->hit = 1;
    out->s0 = s0;
    double f[3], n[3], d[3] = {u[0], u[1], u[2]}, p[3], rgb[3];
    advance(o, u, s0, p);
    if (axis >= 0)
        face(axis, u, -1, f);
    else
        for (int k = 0; k < 3; ++k)
            f[k] = -u[k];
    pick_normal(c, v, f, n);
    shade(c, v, p, n, light, rgb);
    memcpy(out->p[0], p, sizeof(p));
    memcpy(out->n[0], n, sizeof(n));
    memcpy(out->voxel[0], v, sizeof(v));
    if (op->mode == MESO_REF_CELLS_REFLECT) {
        double col[3], w = kr, e[3];
        for (int k = 0; k < 3; ++k)
            col[k] = (1 - kr) * rgb[k];
        reflect(d, n, e);
        if (!(dot3(f, e) > 0))
            reflect(d, f, e);
        memcpy(d, e, sizeof(d));
        memcpy(out->dir[0], d, sizeof(d));
        for (int b = 1; b <= B && axis >= 0; ++b) {
            double s;
            int64_t from[3];
            memcpy(from, last, sizeof(from));
            if (!meso_ref_cells_search(c, p, d, from, HUGE_VAL, 1, &s, v, last, &axis, NULL))
                break;
            advance(p, d, s, p);
            face(axis, d, -1, f);
            pick_normal(c, v, f, n);
            shade(c, v, p, n, light, rgb);
            for (int k = 0; k < 3; ++k)
                col[k] += w * (1 - kr) * rgb[k];
            w *= kr;
            reflect(d, n, e);
            if (!(dot3(f, e) > 0))
                reflect(d, f, e);
            memcpy(d, e, sizeof(d));
            record(out, b, p, n, v, d);
        }
        environment(op, d, e);
        for (int k = 0; k < 3; ++k)
            out->rgb[k] = col[k] + w * e[k];
        return;
    }
    if (op->mode == MESO_REF_CELLS_REFRACT) {
        double e[3];
        int inside = interface(d, n, f, 1 / ior, e);
        memcpy(d, e, sizeof(d));
        memcpy(out->dir[0], d, sizeof(d));
        int64_t from[3];
        memcpy(from, inside ? v : last, sizeof(from));
        for (int b = 1; b <= B && axis >= 0; ++b) {
            double s, g[3];
            int64_t hv[3], hl[3];
            if (!meso_ref_cells_search(c, p, d, from, HUGE_VAL, !inside, &s, hv, hl, &axis, NULL) || axis < 0)
                break;
            advance(p, d, s, p);
            const int64_t* solid_v = inside ? hl : hv; /* leaving: the last SOLID voxel; entering: the one hit */
            if (inside) {
                face(axis, d, 1, f);
                pick_normal(c, hl, f, n);
                for (int k = 0; k < 3; ++k) {
                    n[k] = -n[k];
                    g[k] = -f[k];
                }
                inside = !interface(d, n, g, ior, e);
                memcpy(from, inside ? hl : hv, sizeof(from));
            } else {
                face(axis, d, -1, f);
                pick_normal(c, hv, f, n);
                inside = interface(d, n, f, 1 / ior, e);
                memcpy(from, inside ? hv : hl, sizeof(from));
            }
            memcpy(d, e, sizeof(d));
            record(out, b, p, n, solid_v, d);
        }
        environment(op, d, e);
        for (int k = 0; k < 3; ++k)
            out->rgb[k] = (1 - tau) * rgb[k] + tau * e[k];
        return;
    }
    memcpy(out->rgb, rgb, sizeof(rgb));
}

/* >>render ----------------------------------------------------------------- */

typedef struct cells_scene {
    const meso_ref_cells* c;
    const meso_ref_cells_opts* o;
    mesoi_ref_camera cam;
} cells_scene;

static void cells_row(const cells_scene* sc, meso_ref_image* img, int y)
{
    const int W = img->width, H = img->height;
    for (int x = 0; x < W; ++x) {
        const size_t px = (size_t)y * (size_t)W + (size_t)x;
        double o[3], d[3];
        mesoi_ref_pixel_ray(&sc->cam, x, y, W, H, o, d);
        const double len = normalize3(d);
        meso_ref_cells_path path;
        if (len > 0)
            meso_ref_cells_trace(sc->c, o, d, len, sc->cam.light, sc->o, &path);
        if (!(len > 0) || !path.hit) {
            mesoi_ref_image_miss(img, px);
            continue;
        }
        img->depth[px] = mesoi_ref_depth(&sc->cam, path.p[0]);
        img->coverage[px] = 1;
        for (int k = 0; k < 3; ++k) {
            img->rgb[3 * px + (size_t)k] = (float)path.rgb[k];
            img->hit[3 * px + (size_t)k] = (float)path.p[0][k];
            img->normal[3 * px + (size_t)k] = (float)path.n[0][k];
        }
    }
}

/* mesoi_ref_rows' callback: pixels are independent, so the image does not
 * depend on the partition. */
typedef struct row_ctx {
    const cells_scene* sc;
    meso_ref_image* img;
} row_ctx;

static void row_cb(const void* user, int y)
{
    const row_ctx* r = user;
    cells_row(r->sc, r->img, y);
}

meso_result meso_ref_cells_render(const meso_ref_cells* c, const meso_ref_view* v, const meso_ref_cells_opts* o,
                                  meso_ref_image* out)
{
    if (!c || !v || !out || v->width < 1 || v->height < 1 || v->width > 65536 || v->height > 65536 || !c->tile ||
        !c->memb || !c->normal || !c->colour || c->res == 0 || c->split_count == 0 || !(c->voxel > 0) ||
        (o && (o->mode < MESO_REF_CELLS_FIRST_HIT || o->mode > MESO_REF_CELLS_REFRACT || o->bounces < 0 ||
               o->bounces > 8)))
        return MESO_ERR_INVALID_ARG;
    memset(out, 0, sizeof(*out));
    cells_scene sc;
    memset(&sc, 0, sizeof(sc));
    sc.c = c;
    sc.o = o;
    if (!mesoi_ref_camera_init(v, &sc.cam))
        return MESO_ERR_INVALID_ARG;
    const meso_result r = mesoi_ref_image_alloc(out, v->width, v->height);
    if (r != MESO_OK)
        return r;
    const row_ctx rc = {&sc, out};
    mesoi_ref_rows(v->height, v->threads, row_cb, &rc);
    return MESO_OK;
}
