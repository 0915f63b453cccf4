/*
 * membership.c — pre-merge tags per MIXED tile from 64-voxel words, the
 * §4.5 merge over cell copies, and the sparse encoding. See membership.h.
 */
#include "meso_clock.h"
#include "membership.h"

#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bake_threads.h"

/* >>pre-merge tags ---------------------------------------------------------------
 * Voxel v of a tile is bit v % 64 of word v / 64 of the tile's bits; for
 * every word the split cells with voxels in it and their 64-bit masks are
 * precomputed once, so a tile's tags take one AND per (word, split cell). */
typedef struct wmask {
    uint64_t mask;
    uint32_t split; /* 1..S */
} wmask;

typedef struct builder {
    const meso_split_cells* sc;
    uint32_t T[3], S;
    uint64_t tiles, words;
    int threads;
    uint8_t* cls;      /* pre-merge class per tile (MESO_TILE_*) */
    uint64_t* ids;     /* MIXED tiles, increasing */
    uint8_t* tags;     /* S pre-merge tags per MIXED tile */
    uint64_t count, cap;
    uint32_t* wstart;  /* words + 1 */
    wmask* wm;
    uint8_t* seen;     /* S per thread */
    const uint64_t** batch_bits;
    size_t batch_cap;
} builder;

static meso_result word_masks(builder* B, meso_error* err)
{
    const uint32_t R = B->sc->res;
    const uint64_t n = (uint64_t)R * R * R;
    B->words = (n + 63) / 64;
    B->wstart = malloc(sizeof(uint32_t) * (B->words + 1));
    size_t cap = B->words + 16, m = 0;
    B->wm = malloc(sizeof(wmask) * cap);
    if (!B->wstart || !B->wm)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory");
    for (uint64_t w = 0; w < B->words; ++w) {
        B->wstart[w] = (uint32_t)m;
        const size_t first = m;
        for (uint64_t v = 64 * w; v < n && v < 64 * (w + 1); ++v) {
            const uint32_t s = B->sc->voxel_split[v];
            if (!s)
                continue;
            size_t i = first;
            while (i < m && B->wm[i].split != s)
                ++i;
            if (i == m) {
                if (m == cap) {
                    wmask* grown = realloc(B->wm, sizeof(wmask) * cap * 2);
                    if (!grown)
                        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory");
                    B->wm = grown;
                    cap *= 2;
                }
                B->wm[m++] = (wmask){0, s};
            }
            B->wm[i].mask |= (uint64_t)1 << (v & 63);
        }
    }
    B->wstart[B->words] = (uint32_t)m;
    return MESO_OK;
}

/* Tags of the split cells of one MIXED tile (Table 4.2 over its voxels). */
static void tile_tags(const builder* B, const uint64_t* bits, uint8_t* tags, uint8_t* seen)
{
    memset(seen, 0, B->S);
    for (uint64_t w = 0; w < B->words; ++w) {
        const uint64_t b = bits[w];
        for (uint32_t i = B->wstart[w]; i < B->wstart[w + 1]; ++i) {
            const uint64_t m = B->wm[i].mask;
            seen[B->wm[i].split - 1] |= (uint8_t)(((b & m) != 0) | (((~b & m) != 0) << 1));
        }
    }
    for (uint32_t s = 0; s < B->S; ++s) /* every split cell has a voxel, so seen[s] != 0 */
        tags[s] = seen[s] == 3 ? MESO_MEMB_INTERSECTED : seen[s] == 1 ? MESO_MEMB_INSIDE : MESO_MEMB_OUTSIDE;
}

/* meso_voxel_rows_fn: keep the classes, turn MIXED tiles into tags. */
static meso_result take_rows(void* user, const meso_voxel_row* rows, uint32_t n, meso_error* err)
{
    builder* B = user;
    const uint32_t T0 = B->T[0], T1 = B->T[1];
    uint64_t add = 0;
    for (uint32_t r = 0; r < n; ++r) {
        memcpy(B->cls + (uint64_t)T0 * (rows[r].ty + (uint64_t)T1 * rows[r].tz), rows[r].classes, T0);
        add += rows[r].mixed_count;
    }
    if (B->count + add > B->cap) {
        uint64_t c = B->cap ? B->cap : 256;
        while (c < B->count + add)
            c *= 2;
        uint64_t* ids = realloc(B->ids, c * sizeof(uint64_t));
        if (ids)
            B->ids = ids;
        uint8_t* tags = ids && B->S ? realloc(B->tags, c * B->S) : B->tags;
        if (!ids || (B->S && !tags))
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory (%llu mixed tiles)",
                                  (unsigned long long)c);
        B->tags = tags;
        B->cap = c;
    }
    if (add > B->batch_cap) {
        const uint64_t** p = realloc(B->batch_bits, add * sizeof(*p));
        if (!p)
            return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory");
        B->batch_bits = p;
        B->batch_cap = add;
    }
    uint64_t k = 0;
    for (uint32_t r = 0; r < n; ++r)
        for (uint32_t i = 0; i < rows[r].mixed_count; ++i, ++k) {
            B->ids[B->count + k] = rows[r].mixed_tx[i] + (uint64_t)T0 * (rows[r].ty + (uint64_t)T1 * rows[r].tz);
            B->batch_bits[k] = rows[r].bits + i * B->words;
        }
    const uint64_t base = B->count;
    const int nt = B->threads;
    (void)nt;
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 16) num_threads(nt)
#endif
    for (long i = 0; i < (long)add; ++i) {
#ifdef _OPENMP
        uint8_t* seen = B->seen + (size_t)omp_get_thread_num() * B->S;
#else
        uint8_t* seen = B->seen;
#endif
        tile_tags(B, B->batch_bits[i], B->tags + (base + (uint64_t)i) * B->S, seen);
    }
    B->count += add;
    return MESO_OK;
}

/* >>merge ------------------------------------------------------------------------ */

typedef struct disp {
    int32_t d[3];
} disp;

static int cmp_disp(const void* pa, const void* pb)
{
    const disp *a = pa, *b = pb;
    for (int k = 0; k < 3; ++k)
        if (a->d[k] != b->d[k])
            return a->d[k] < b->d[k] ? -1 : 1;
    return 0;
}

typedef struct merger {
    const builder* B;
    disp* D;            /* distinct offset(s') - offset(s) within a cell */
    uint32_t nd;
    uint32_t* pd;       /* per cell c, count_c^2 indices into D: [a count + b] for splits first+a, first+b */
    uint64_t* pbase;    /* cells + 1 */
    int32_t lo[3], hi[3]; /* range of D per axis */
} merger;

static meso_result build_displacements(merger* M, meso_error* err)
{
    const meso_split_cells* sc = M->B->sc;
    uint64_t pairs = 0;
    M->pbase = malloc(sizeof(uint64_t) * ((size_t)sc->cell_count + 1));
    if (!M->pbase)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory");
    for (uint32_t c = 0; c < sc->cell_count; ++c) {
        M->pbase[c] = pairs;
        pairs += (uint64_t)sc->cells[c].split_count * sc->cells[c].split_count;
    }
    M->pbase[sc->cell_count] = pairs;
    M->pd = malloc(sizeof(uint32_t) * (pairs ? pairs : 1));
    disp* all = malloc(sizeof(disp) * (pairs ? pairs : 1));
    if (!M->pd || !all) {
        free(all);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory (%llu split pairs)",
                              (unsigned long long)pairs);
    }
    uint64_t n = 0;
    for (uint32_t c = 0; c < sc->cell_count; ++c) {
        const meso_cell* cell = &sc->cells[c];
        for (uint32_t a = 0; a < cell->split_count; ++a)
            for (uint32_t b = 0; b < cell->split_count; ++b) {
                const int32_t* oa = sc->splits[cell->first_split - 1 + a].offset;
                const int32_t* ob = sc->splits[cell->first_split - 1 + b].offset;
                all[n++] = (disp){{ob[0] - oa[0], ob[1] - oa[1], ob[2] - oa[2]}};
            }
    }
    disp* sorted = malloc(sizeof(disp) * (pairs ? pairs : 1));
    if (!sorted) {
        free(all);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory");
    }
    memcpy(sorted, all, sizeof(disp) * n);
    qsort(sorted, n, sizeof(disp), cmp_disp);
    uint32_t nd = 0;
    for (uint64_t i = 0; i < n; ++i)
        if (nd == 0 || cmp_disp(&sorted[nd - 1], &sorted[i]) != 0)
            sorted[nd++] = sorted[i];
    for (uint64_t i = 0; i < n; ++i) { /* index of each pair's displacement */
        uint32_t lo = 0, hi = nd;
        while (lo < hi) {
            const uint32_t mid = lo + (hi - lo) / 2;
            if (cmp_disp(&sorted[mid], &all[i]) < 0)
                lo = mid + 1;
            else
                hi = mid;
        }
        M->pd[i] = lo;
    }
    free(all);
    M->D = sorted;
    M->nd = nd;
    for (int k = 0; k < 3; ++k) {
        M->lo[k] = M->hi[k] = 0;
        for (uint32_t i = 0; i < nd; ++i) {
            M->lo[k] = sorted[i].d[k] < M->lo[k] ? sorted[i].d[k] : M->lo[k];
            M->hi[k] = sorted[i].d[k] > M->hi[k] ? sorted[i].d[k] : M->hi[k];
        }
    }
    return MESO_OK;
}

/* Tile t + d: its id, or -1 beyond the grid. */
static int64_t neighbour(const builder* B, uint64_t t, const int32_t d[3])
{
    const uint32_t T0 = B->T[0], T1 = B->T[1];
    const int64_t x = (int64_t)(t % T0) + d[0], y = (int64_t)(t / T0 % T1) + d[1], z = (int64_t)(t / T0 / T1) + d[2];
    if (x < 0 || y < 0 || z < 0 || x >= T0 || y >= T1 || z >= B->T[2])
        return -1;
    return x + (int64_t)T0 * (y + (int64_t)T1 * z);
}

static const uint8_t* mixed_tags(const builder* B, uint64_t t)
{
    uint64_t lo = 0, hi = B->count;
    while (lo < hi) {
        const uint64_t mid = lo + (hi - lo) / 2;
        if (B->ids[mid] < t)
            lo = mid + 1;
        else
            hi = mid;
    }
    return B->tags + lo * B->S;
}

/* Merged tags of every split cell of tile t (Algorithm 4.6 per copy). */
static void merge_tile(const merger* M, uint64_t t, uint8_t* out, uint8_t* ncls, const uint8_t** ntags)
{
    const builder* B = M->B;
    const meso_split_cells* sc = B->sc;
    for (uint32_t k = 0; k < M->nd; ++k) {
        const int64_t u = neighbour(B, t, M->D[k].d);
        ncls[k] = u < 0 ? MESO_TILE_OUTSIDE : B->cls[u];
        ntags[k] = u >= 0 && ncls[k] == MESO_TILE_MIXED ? mixed_tags(B, (uint64_t)u) : NULL;
    }
    for (uint32_t s = 1; s <= B->S; ++s) {
        const uint32_t c = sc->splits[s - 1].cell, first = sc->cells[c - 1].first_split;
        const uint32_t n = sc->cells[c - 1].split_count, a = s - first;
        const uint32_t* pd = M->pd + M->pbase[c - 1] + (uint64_t)a * n;
        meso_memb_tag acc = MESO_MEMB_UNSET;
        for (uint32_t b = 0; b < n && acc != MESO_MEMB_INTERSECTED; ++b) {
            const uint32_t k = pd[b];
            const meso_memb_tag tag = ntags[k] ? (meso_memb_tag)ntags[k][first + b - 1] : (meso_memb_tag)ncls[k];
            acc = meso_memb_combine(acc, tag);
        }
        out[s - 1] = (uint8_t)acc;
    }
}

/* >>encoding --------------------------------------------------------------------- */

static void set_class(uint32_t* classes, uint64_t t, uint32_t c)
{
    classes[t / 16] |= c << (2 * (t % 16));
}

meso_tile_class meso_membership_tile(const meso_membership* mb, uint32_t tx, uint32_t ty, uint32_t tz)
{
    const uint64_t t = tx + (uint64_t)mb->tiles[0] * (ty + (uint64_t)mb->tiles[1] * tz);
    return (meso_tile_class)((mb->classes[t / 16] >> (2 * (t % 16))) & 3u);
}

meso_memb_tag meso_membership_get(const meso_membership* mb, uint32_t tx, uint32_t ty, uint32_t tz, uint32_t split)
{
    const uint64_t t = tx + (uint64_t)mb->tiles[0] * (ty + (uint64_t)mb->tiles[1] * tz);
    const uint32_t word = mb->classes[t / 16], c = (word >> (2 * (t % 16))) & 3u;
    if (c != MESO_TILE_MIXED)
        return (meso_memb_tag)c; /* OUTSIDE / INSIDE: every split cell alike */
    const uint32_t below = (uint32_t)((((uint64_t)1 << (2 * (t % 16))) - 1) & word);
    const uint64_t rec = mb->rank[t / 16] + (uint64_t)__builtin_popcount(below & 0xAAAAAAAAu);
    const uint32_t* r = mb->records + rec * mb->words_per_tile;
    return (meso_memb_tag)((r[(split - 1) / 16] >> (2 * ((split - 1) % 16))) & 3u);
}

void meso_membership_free(meso_membership* mb)
{
    if (!mb)
        return;
    free(mb->classes);
    free(mb->rank);
    free(mb->records);
    memset(mb, 0, sizeof(*mb));
}

/* >>driver ------------------------------------------------------------------------- */


static void builder_free(builder* B)
{
    free(B->cls);
    free(B->ids);
    free(B->tags);
    free(B->wstart);
    free(B->wm);
    free(B->seen);
    free(B->batch_bits);
}

static meso_result builder_init(builder* B, const meso_voxel_grid* g, const meso_split_cells* sc, int threads,
                                meso_error* err)
{
    memset(B, 0, sizeof(*B));
    if (!g || !sc || (sc->split_count && (!sc->voxel_split || !sc->splits || !sc->cells)))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "membership: NULL argument");
    if (sc->res != g->tile_res)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_MEMB_ISSUE_MISMATCH,
                              "membership: the tile map has %u^3 voxels, the grid's tiles %u^3", sc->res,
                              g->tile_res);
    B->sc = sc;
    B->S = sc->split_count;
    B->threads = meso_bake_thread_count(threads);
    memcpy(B->T, g->tiles, sizeof(B->T));
    B->tiles = (uint64_t)g->tiles[0] * g->tiles[1] * g->tiles[2];
    B->cls = malloc(B->tiles ? B->tiles : 1);
    B->seen = malloc((size_t)B->threads * (B->S ? B->S : 1));
    if (!B->cls || !B->seen)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory (%llu tiles)",
                              (unsigned long long)B->tiles);
    return word_masks(B, err);
}

/* Merge, classify and encode; B holds the pre-merge state. */
static meso_result finish(builder* B, meso_membership* out, meso_error* err)
{
    const meso_split_cells* sc = B->sc;
    const uint64_t T = B->tiles, nwords = (T + 15) / 16;
    const uint32_t S = B->S, W = (2 * S + 31) / 32;
    merger M = {.B = B};
    meso_result r = build_displacements(&M, err);
    uint8_t* aff = r == MESO_OK ? calloc(T ? T : 1, 1) : NULL;
    uint64_t* list = NULL;
    uint8_t* merged = NULL;
    uint8_t* ncls = NULL;
    const uint8_t** ntags = NULL;
    out->classes = calloc(nwords ? nwords : 1, sizeof(uint32_t));
    out->rank = calloc(nwords ? nwords : 1, sizeof(uint32_t));
    if (r == MESO_OK && (!aff || !out->classes || !out->rank))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory (%llu tiles)",
                           (unsigned long long)T);
    if (r != MESO_OK)
        goto done;
    memcpy(out->tiles, B->T, sizeof(out->tiles));
    out->split_count = S;
    out->words_per_tile = W;
    out->tile_count = T;

    /* 1. Tiles a merge can change: MIXED ones, and uniform ones with a copy
     * reaching a tile of another class (beyond the grid: OUTSIDE). */
    const int nt = B->threads;
    (void)nt;
    if (S) {
#ifdef _OPENMP
#pragma omp parallel for schedule(static) num_threads(nt)
#endif
        for (long i = 0; i < (long)T; ++i) {
            const uint64_t t = (uint64_t)i;
            uint8_t a = B->cls[t] == MESO_TILE_MIXED;
            for (uint32_t k = 0; k < M.nd && !a; ++k) {
                const int64_t u = neighbour(B, t, M.D[k].d);
                a = (u < 0 ? MESO_TILE_OUTSIDE : B->cls[u]) != B->cls[t];
            }
            aff[t] = a;
        }
    }
    uint64_t na = 0;
    for (uint64_t t = 0; t < T; ++t)
        na += aff[t];
    list = malloc(sizeof(uint64_t) * (na ? na : 1));
    merged = malloc(na * S + 1);
    ncls = malloc((size_t)nt * (M.nd ? M.nd : 1));
    ntags = malloc(sizeof(*ntags) * (size_t)nt * (M.nd ? M.nd : 1));
    if (!list || !merged || !ncls || !ntags) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory (%llu tiles to merge)",
                           (unsigned long long)na);
        goto done;
    }
    na = 0;
    for (uint64_t t = 0; t < T; ++t)
        if (aff[t])
            list[na++] = t;

    /* 2. Merge them (each independently). */
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 64) num_threads(nt)
#endif
    for (long i = 0; i < (long)na; ++i) {
#ifdef _OPENMP
        const int me = omp_get_thread_num();
#else
        const int me = 0;
#endif
        merge_tile(&M, list[i], merged + (uint64_t)i * S, ncls + (size_t)me * M.nd, ntags + (size_t)me * M.nd);
    }

    /* 3. Classes after the merge, records, counts. */
    uint64_t records = 0;
    for (uint64_t i = 0; i < na; ++i) {
        const uint8_t* m = merged + i * S;
        int all_in = 1, all_out = 1;
        for (uint32_t s = 0; s < S; ++s) {
            all_in &= m[s] == MESO_MEMB_INSIDE;
            all_out &= m[s] == MESO_MEMB_OUTSIDE;
        }
        records += !all_in && !all_out;
    }
    if (records > UINT32_MAX || records * W > ((uint64_t)1 << 40)) {
        r = meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_MEMB_ISSUE_SIZE, /* --tiles/--tile-res: exit 1 */
                           "membership: %llu mixed tiles of %u words: too large for the encoding",
                           (unsigned long long)records, W);
        goto done;
    }
    out->records = malloc(sizeof(uint32_t) * (records * W + 1));
    if (!out->records) {
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory (%llu records)",
                           (unsigned long long)records);
        goto done;
    }
    memset(out->records, 0, sizeof(uint32_t) * records * W);
    uint64_t ai = 0, rec = 0;
    for (uint64_t t = 0; t < T; ++t) {
        if (t % 16 == 0)
            out->rank[t / 16] = (uint32_t)rec;
        uint32_t c;
        if (!S) {
            c = MESO_TILE_OUTSIDE;
        } else if (!aff[t]) {
            c = B->cls[t];
        } else {
            const uint8_t* m = merged + ai * S;
            const uint8_t* pre = B->cls[t] == MESO_TILE_MIXED ? mixed_tags(B, t) : NULL;
            int all_in = 1, all_out = 1, changed = 0;
            for (uint32_t s = 0; s < S; ++s) {
                all_in &= m[s] == MESO_MEMB_INSIDE;
                all_out &= m[s] == MESO_MEMB_OUTSIDE;
                changed |= m[s] != (pre ? pre[s] : B->cls[t]);
            }
            out->tiles_merge_changed += changed;
            c = all_in ? MESO_TILE_INSIDE : all_out ? MESO_TILE_OUTSIDE : MESO_TILE_MIXED;
            if (c == MESO_TILE_MIXED) {
                uint32_t* dst = out->records + rec * W;
                for (uint32_t s = 0; s < S; ++s)
                    dst[s / 16] |= (uint32_t)m[s] << (2 * (s % 16));
                ++rec;
            }
            ++ai;
        }
        set_class(out->classes, t, c);
        out->tiles_outside += c == MESO_TILE_OUTSIDE;
        out->tiles_inside += c == MESO_TILE_INSIDE;
        out->tiles_mixed += c == MESO_TILE_MIXED;
    }
    out->record_count = rec;
    out->bytes = sizeof(uint32_t) * (2 * nwords + rec * W);

    /* Cell copies: each counted at its first split cell (lowest id) whose
     * tile is in the grid. In a tile every copy of which lies in the grid,
     * that is each cell's first split cell. */
    uint64_t cnt[3] = {0, 0, 0}, wrap = 0;
    for (uint64_t t = 0; S && t < T; ++t) {
        const uint32_t x = (uint32_t)(t % B->T[0]), y = (uint32_t)(t / B->T[0] % B->T[1]),
                       z = (uint32_t)(t / B->T[0] / B->T[1]);
        const int interior = (int64_t)x + M.lo[0] >= 0 && (int64_t)x + M.hi[0] < B->T[0] &&
                             (int64_t)y + M.lo[1] >= 0 && (int64_t)y + M.hi[1] < B->T[1] &&
                             (int64_t)z + M.lo[2] >= 0 && (int64_t)z + M.hi[2] < B->T[2];
        const meso_tile_class c = meso_membership_tile(out, x, y, z);
        if (interior && c != MESO_TILE_MIXED) {
            cnt[c] += sc->cell_count;
            wrap += sc->wrapping_cells;
            continue;
        }
        for (uint32_t s = 1; s <= S; ++s) {
            const uint32_t cell = sc->splits[s - 1].cell, first = sc->cells[cell - 1].first_split;
            const uint32_t n = sc->cells[cell - 1].split_count, a = s - first;
            const uint32_t* pd = M.pd + M.pbase[cell - 1] + (uint64_t)a * n;
            int rep = 1;
            for (uint32_t b = 0; b < a && rep; ++b)
                rep = neighbour(B, t, M.D[pd[b]].d) < 0;
            if (!rep)
                continue;
            cnt[meso_membership_get(out, x, y, z, s)]++;
            wrap += sc->cells[cell - 1].wraps;
        }
    }
    out->cells_outside = cnt[MESO_MEMB_OUTSIDE];
    out->cells_inside = cnt[MESO_MEMB_INSIDE];
    out->cells_intersected = cnt[MESO_MEMB_INTERSECTED];
    out->wrapping_copies = wrap;
done:
    free(M.D);
    free(M.pd);
    free(M.pbase);
    free(aff);
    free(list);
    free(merged);
    free(ncls);
    free(ntags);
    return r;
}

/* Merge and encode when all went well; free the builder; time the call. */
static meso_result conclude(builder* B, meso_result r, double t0, meso_membership* out, meso_error* err)
{
    if (r == MESO_OK)
        r = finish(B, out, err);
    builder_free(B);
    if (r != MESO_OK)
        meso_membership_free(out);
    else
        out->seconds = meso_seconds() - t0;
    return r;
}

meso_result meso_membership_compute(const meso_mesh* m, const meso_voxel_grid* g, const meso_split_cells* sc,
                                    meso_voxelizer method, int threads, meso_membership* out, meso_error* err)
{
    const double t0 = meso_seconds();
    if (!out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "membership: NULL argument");
    memset(out, 0, sizeof(*out));
    builder B;
    meso_result r = builder_init(&B, g, sc, threads, err);
    if (r == MESO_OK)
        r = meso_voxelize_stream(m, g, method, threads, take_rows, &B, &out->voxelize, err);
    return conclude(&B, r, t0, out, err);
}

meso_result meso_membership_from_voxels(const meso_voxels* v, const meso_split_cells* sc, int threads,
                                        meso_membership* out, meso_error* err)
{
    const double t0 = meso_seconds();
    if (!out || !v)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "membership: NULL argument");
    memset(out, 0, sizeof(*out));
    builder B;
    meso_result r = builder_init(&B, &v->grid, sc, threads, err);
    const uint32_t T0 = v->grid.tiles[0], T1 = v->grid.tiles[1], nrows = T1 * v->grid.tiles[2];
    meso_voxel_row* rows = r == MESO_OK ? malloc(sizeof(meso_voxel_row) * (nrows ? nrows : 1)) : NULL;
    uint32_t* tx = r == MESO_OK ? malloc(sizeof(uint32_t) * (v->mixed_count ? v->mixed_count : 1)) : NULL;
    if (r == MESO_OK && (!rows || !tx))
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "membership: out of memory");
    if (r == MESO_OK) { /* the kept result, handed over as the stream would */
        uint64_t k = 0;
        for (uint32_t row = 0; row < nrows; ++row) {
            const uint64_t first = k, base = (uint64_t)T0 * row;
            while (k < v->mixed_count && v->mixed_tiles[k] < base + T0) {
                tx[k] = (uint32_t)(v->mixed_tiles[k] - base);
                ++k;
            }
            rows[row] = (meso_voxel_row){row % T1, row / T1, v->tile_class + base, (uint32_t)(k - first),
                                         tx + first, k > first ? v->bits + first * v->tile_words : NULL};
        }
        r = take_rows(&B, rows, nrows, err);
    }
    free(rows);
    free(tx);
    return conclude(&B, r, t0, out, err);
}
