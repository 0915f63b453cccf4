/*
 * voxelize.c — sparse inside/outside voxelization by exact ray crossings
 * along x, per tile row. See voxelize.h for the method, the perturbation
 * and the two paths; voxelize_internal.h lists the files that do the work.
 * This one holds the driver (tile rows in batches, on threads) and the
 * stored result.
 */
#include "meso_clock.h"
#include "voxelize.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bake_threads.h"
#include "voxelize_internal.h"

/* >>driver ----------------------------------------------------------------------- */


static meso_result check_mesh(const meso_mesh* m, meso_error* err)
{
    if (m->triangle_count == 0 || m->vertex_count == 0 || !m->positions || !m->indices)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH, "voxelize: the mesh is empty");
    if (m->vertex_count >= 0x7FFFFFFFu)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH,
                              "voxelize: %u vertices: at most 2^31 - 2", m->vertex_count);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; ++i)
        if (m->indices[i] >= m->vertex_count)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH,
                                  "voxelize: face %zu refers to vertex %u of %u", i / 3, m->indices[i],
                                  m->vertex_count);
    for (size_t i = 0; i < 3 * (size_t)m->vertex_count; ++i)
        if (!isfinite(m->positions[i]))
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_VOXELIZE_ISSUE_MESH,
                                  "voxelize: vertex %zu has a non-finite coordinate", i / 3);
    return MESO_OK;
}

/* Triangles per z-layer of tiles, as CSR: start[T2 + 1], items. */
static int bin_layers(const mesoi_grid* g, const mesoi_soup* s, uint32_t* start, uint32_t** items, size_t* cap)
{
    const uint32_t T = g->T[2];
    memset(start, 0, sizeof(uint32_t) * ((size_t)T + 1));
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t t = 0; t < s->count; ++t) {
            double v[3][3], lo[3], hi[3];
            uint32_t a, b, c, d;
            mesoi_tri_corners(s, t, v, lo, hi);
            if (!mesoi_tile_span(g, 2, lo[2], hi[2], &a, &b) || !mesoi_tile_span(g, 1, lo[1], hi[1], &c, &d))
                continue; /* outside the grid in z or y: no row of it meets the triangle */
            for (uint32_t k = a; k <= b; ++k) {
                if (pass == 0)
                    start[k + 1]++;
                else
                    (*items)[start[k]++] = t;
            }
        }
        if (pass == 0 && !mesoi_csr_counted(start, T, items, cap))
            return 0;
    }
    mesoi_csr_filled(start, T);
    return 1;
}

/* Triangles per tile row r = ty + T1 tz for rows [r0, r1), as CSR over
 * r - r0, from the layer lists. */
static int bin_rows_of_batch(const mesoi_grid* g, const mesoi_soup* s, const uint32_t* lstart, const uint32_t* litems,
                             uint64_t r0, uint64_t r1, uint32_t* start, uint32_t** items, size_t* cap)
{
    const uint32_t T1 = g->T[1];
    const uint64_t n = r1 - r0;
    memset(start, 0, sizeof(uint32_t) * ((size_t)n + 1));
    for (int pass = 0; pass < 2; ++pass) {
        for (uint32_t tz = (uint32_t)(r0 / T1); tz <= (uint32_t)((r1 - 1) / T1); ++tz)
            for (uint32_t i = lstart[tz]; i < lstart[tz + 1]; ++i) {
                double v[3][3], lo[3], hi[3];
                uint32_t a, b;
                mesoi_tri_corners(s, litems[i], v, lo, hi);
                if (!mesoi_tile_span(g, 1, lo[1], hi[1], &a, &b))
                    continue;
                for (uint32_t ty = a; ty <= b; ++ty) {
                    const uint64_t r = ty + (uint64_t)T1 * tz;
                    if (r < r0 || r >= r1)
                        continue;
                    if (pass == 0)
                        start[r - r0 + 1]++;
                    else
                        (*items)[start[r - r0]++] = litems[i];
                }
            }
        if (pass == 0 && !mesoi_csr_counted(start, n, items, cap))
            return 0;
    }
    mesoi_csr_filled(start, n);
    return 1;
}

/* Per-thread working memory for tile rows of R^2 voxel rows and T0 tiles
 * (the rest grows on demand); 0 when out of memory. */
static int scratch_alloc(mesoi_scratch* sc, uint32_t R, uint32_t T0)
{
    sc->bstart = malloc(sizeof(uint32_t) * ((size_t)R * R + 1));
    sc->cand = malloc(T0);
    sc->ctx = malloc(sizeof(uint32_t) * T0);
    sc->twc = malloc(sizeof(double) * T0);
    sc->tspread = malloc(sizeof(double) * T0);
    return sc->bstart && sc->cand && sc->ctx && sc->twc && sc->tspread;
}

/* Adds sc's counters to st, then frees sc's memory. */
static void scratch_free(mesoi_scratch* sc, meso_voxelize_stats* st)
{
    st->rows += sc->n.rows;
    st->crossings += sc->n.crossings;
    st->exact_predicates += sc->n.exact;
    st->voxels_evaluated += sc->n.evaluated;
    st->tiles_candidate += sc->n.candidates;
    free(sc->xs);
    free(sc->lt);
    free(sc->bstart);
    free(sc->bucket);
    free(sc->cand);
    free(sc->ctx);
    free(sc->twc);
    free(sc->tspread);
}

/* The rows r0 .. r0 + nb - 1 of a batch as the caller gets them, counted
 * into st. */
static void batch_rows(const mesoi_row_out* outs, uint64_t r0, uint32_t nb, uint32_t T0, uint32_t T1,
                       meso_voxel_row* rows, meso_voxelize_stats* st)
{
    for (uint32_t b = 0; b < nb; ++b) {
        const uint64_t row = r0 + b;
        rows[b] = (meso_voxel_row){(uint32_t)(row % T1), (uint32_t)(row / T1), outs[b].classes,
                                   outs[b].mixed_count, outs[b].mixed_tx, outs[b].bits};
        for (uint32_t t = 0; t < T0; ++t) {
            st->tiles_outside += outs[b].classes[t] == MESO_TILE_OUTSIDE;
            st->tiles_inside += outs[b].classes[t] == MESO_TILE_INSIDE;
            st->tiles_mixed += outs[b].classes[t] == MESO_TILE_MIXED;
        }
    }
}

/* Tile rows handed to the caller at once, in (tz, ty) order: as many as
 * keep the MIXED bits of a batch near BATCH_BITS_BYTES (assuming 4
 * candidate tiles per row) and its classes near BATCH_CLASS_BYTES, but at
 * least BATCH_PER_THREAD per thread. Few, long parallel regions matter on a
 * loaded machine: with more threads than free cores, an OpenMP barrier per
 * handful of rows made 2 threads 30x slower than 1 here. */
#define BATCH_PER_THREAD 4
#define BATCH_BITS_BYTES ((uint64_t)64 << 20)
#define BATCH_CLASS_BYTES ((uint64_t)16 << 20)

meso_result meso_voxelize_stream(const meso_mesh* m, const meso_voxel_grid* vg, meso_voxelizer method, int threads,
                                 meso_voxel_rows_fn fn, void* user, meso_voxelize_stats* stats, meso_error* err)
{
    const double t_start = meso_seconds();
    if (!m || !vg || !fn || method < 0 || method >= MESO_VOXELIZE_COUNT)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "voxelize: NULL or bad argument");
    mesoi_grid g;
    meso_result r = mesoi_check_grid(vg, &g, err);
    if (r == MESO_OK)
        r = check_mesh(m, err);
    if (r != MESO_OK)
        return r;
    const int nt = meso_bake_thread_count(threads);
    mesoi_soup s;
    r = mesoi_soup_build(m, &method, nt, &s, err);
    if (r != MESO_OK)
        return r;

    const uint32_t R = g.R, T0 = g.T[0], T1 = g.T[1], T2 = g.T[2];
    const uint64_t total_rows = (uint64_t)T1 * T2, words = meso_voxel_tile_words(R);
    uint64_t want = BATCH_BITS_BYTES / (4 * words * 8);
    if (want > BATCH_CLASS_BYTES / T0)
        want = BATCH_CLASS_BYTES / T0;
    if (want < (uint64_t)nt * BATCH_PER_THREAD)
        want = (uint64_t)nt * BATCH_PER_THREAD;
    const uint32_t batch = (uint32_t)(want < total_rows ? want : total_rows);
    uint32_t *lstart = malloc(sizeof(uint32_t) * ((size_t)T2 + 1)), *ystart = malloc(sizeof(uint32_t) * ((size_t)batch + 1));
    uint32_t *litems = NULL, *yitems = NULL;
    size_t lcap = 0, ycap = 0;
    float(*bedge)[6] = NULL;
    mesoi_scratch* sc = calloc((size_t)nt, sizeof(mesoi_scratch));
    mesoi_row_out* outs = calloc(batch, sizeof(mesoi_row_out));
    meso_voxel_row* rows = calloc(batch, sizeof(meso_voxel_row));
    int ok = lstart && ystart && sc && outs && rows;
    for (int t = 0; ok && t < nt; ++t)
        ok = scratch_alloc(&sc[t], R, T0);
    for (uint32_t b = 0; ok && b < batch; ++b)
        ok = (outs[b].classes = malloc(T0)) != NULL;
    const uint32_t ncone = s.count - s.surface;
    if (ok && ncone) {
        ok = (bedge = malloc(sizeof(*bedge) * ncone)) != NULL;
        for (uint32_t e = 0; ok && e < ncone; ++e) /* cone triangle (b, a, apex) of edge a -> b */
            for (int k = 0; k < 3; ++k) {
                bedge[e][k] = s.pos[3 * (size_t)s.idx[3 * ((size_t)s.surface + e) + 1] + (size_t)k];
                bedge[e][3 + k] = s.pos[3 * (size_t)s.idx[3 * ((size_t)s.surface + e)] + (size_t)k];
            }
    }
    if (ok)
        ok = bin_layers(&g, &s, lstart, &litems, &lcap);
    if (!ok)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory");

    meso_voxelize_stats st = {0};
    st.method = method;
    st.voxels = (uint64_t)g.N[0] * g.N[1] * g.N[2];
    st.tiles = (uint64_t)T0 * T1 * T2;
    st.boundary_edges = st.cone_triangles = ncone;
    for (uint64_t r0 = 0; r == MESO_OK && r0 < total_rows; r0 += batch) {
        const uint32_t nb = (uint32_t)(total_rows - r0 < batch ? total_rows - r0 : batch);
        if (!bin_rows_of_batch(&g, &s, lstart, litems, r0, r0 + nb, ystart, &yitems, &ycap)) {
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory");
            break;
        }
        int oom = 0;
#ifdef _OPENMP
#pragma omp parallel for schedule(dynamic, 1) num_threads(nt) reduction(| : oom)
#endif
        for (long b = 0; b < (long)nb; ++b) {
#ifdef _OPENMP
            mesoi_scratch* mine = &sc[omp_get_thread_num()];
#else
            mesoi_scratch* mine = &sc[0];
#endif
            const uint64_t row = r0 + (uint64_t)b;
            const mesoi_job jb = {.g = &g,
                            .s = &s,
                            .method = method,
                            .list = yitems + ystart[b],
                            .list_count = ystart[b + 1] - ystart[b],
                            .ty = (uint32_t)(row % T1),
                            .tz = (uint32_t)(row / T1),
                            .bedge = (const float(*)[6])bedge,
                            .bedge_count = ncone};
            mine->oom = 0;
            mesoi_process_row(&jb, mine, &outs[b]);
            oom |= mine->oom;
        }
        if (oom) {
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (tile row)");
        } else {
            batch_rows(outs, r0, nb, T0, T1, rows, &st);
            const meso_result rf = fn(user, rows, nb, err);
            if (rf != MESO_OK) {
                if (err)
                    err->code = MESO_VOXELIZE_ISSUE_STOPPED;
                r = rf;
            }
        }
        for (uint32_t b = 0; b < nb; ++b) {
            free(outs[b].mixed_tx);
            free(outs[b].bits);
            outs[b].mixed_tx = NULL;
            outs[b].bits = NULL;
        }
    }
    for (int t = 0; sc && t < nt; ++t)
        scratch_free(&sc[t], &st);
    for (uint32_t b = 0; outs && b < batch; ++b)
        free(outs[b].classes);
    free(sc);
    free(outs);
    free(rows);
    free(lstart);
    free(ystart);
    free(litems);
    free(yitems);
    free(bedge);
    mesoi_soup_free(&s);
    st.seconds = meso_seconds() - t_start;
    if (stats)
        *stats = st;
    return r;
}

/* >>stored result ------------------------------------------------------------------ */

typedef struct store {
    meso_voxels* v;
    uint64_t cap;
} store;

static meso_result store_rows(void* user, const meso_voxel_row* rows, uint32_t n, meso_error* err)
{
    store* st = user;
    meso_voxels* v = st->v;
    const uint32_t T0 = v->grid.tiles[0], T1 = v->grid.tiles[1];
    for (uint32_t r = 0; r < n; ++r) {
        const meso_voxel_row* row = &rows[r];
        const uint64_t base = (uint64_t)T0 * (row->ty + (uint64_t)T1 * row->tz);
        memcpy(v->tile_class + base, row->classes, T0);
        if (v->mixed_count + row->mixed_count > st->cap) {
            uint64_t c = st->cap ? st->cap : 64;
            while (c < v->mixed_count + row->mixed_count)
                c *= 2;
            uint64_t* ids = realloc(v->mixed_tiles, c * sizeof(uint64_t));
            if (ids)
                v->mixed_tiles = ids;
            uint64_t* bits = ids ? realloc(v->bits, c * v->tile_words * sizeof(uint64_t)) : NULL;
            if (!bits)
                return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (%llu mixed tiles)",
                                      (unsigned long long)c);
            v->bits = bits;
            st->cap = c;
        }
        if (!row->mixed_count)
            continue;
        for (uint32_t i = 0; i < row->mixed_count; ++i)
            v->mixed_tiles[v->mixed_count + i] = base + row->mixed_tx[i];
        memcpy(v->bits + v->mixed_count * v->tile_words, row->bits,
               (size_t)row->mixed_count * v->tile_words * sizeof(uint64_t));
        v->mixed_count += row->mixed_count;
    }
    return MESO_OK;
}

meso_result meso_voxelize(const meso_mesh* m, const meso_voxel_grid* g, meso_voxelizer method, int threads,
                          meso_voxels* out, meso_error* err)
{
    if (!out || !g)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "voxelize: NULL argument");
    memset(out, 0, sizeof(*out));
    mesoi_grid gi;
    meso_result r = mesoi_check_grid(g, &gi, err);
    if (r != MESO_OK)
        return r;
    out->grid = *g;
    out->tile_words = meso_voxel_tile_words(g->tile_res);
    const uint64_t tiles = (uint64_t)g->tiles[0] * g->tiles[1] * g->tiles[2];
    out->tile_class = malloc(tiles);
    if (!out->tile_class)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "voxelize: out of memory (%llu tiles)",
                              (unsigned long long)tiles);
    store st = {out, 0};
    r = meso_voxelize_stream(m, g, method, threads, store_rows, &st, &out->stats, err);
    if (r != MESO_OK)
        meso_voxels_free(out);
    return r;
}

meso_tile_class meso_voxels_tile(const meso_voxels* v, uint32_t tx, uint32_t ty, uint32_t tz)
{
    return (meso_tile_class)
        v->tile_class[tx + (uint64_t)v->grid.tiles[0] * (ty + (uint64_t)v->grid.tiles[1] * tz)];
}

const uint64_t* meso_voxels_tile_bits(const meso_voxels* v, uint32_t tx, uint32_t ty, uint32_t tz)
{
    const uint64_t id = tx + (uint64_t)v->grid.tiles[0] * (ty + (uint64_t)v->grid.tiles[1] * tz);
    uint64_t lo = 0, hi = v->mixed_count;
    while (lo < hi) {
        const uint64_t mid = lo + (hi - lo) / 2;
        if (v->mixed_tiles[mid] < id)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < v->mixed_count && v->mixed_tiles[lo] == id ? v->bits + lo * v->tile_words : NULL;
}

int meso_voxels_inside(const meso_voxels* v, uint32_t i, uint32_t j, uint32_t k)
{
    const uint32_t R = v->grid.tile_res;
    const meso_tile_class c = meso_voxels_tile(v, i / R, j / R, k / R);
    if (c != MESO_TILE_MIXED)
        return c == MESO_TILE_INSIDE;
    const uint64_t* bits = meso_voxels_tile_bits(v, i / R, j / R, k / R);
    const uint64_t bit = i % R + (uint64_t)R * (j % R + (uint64_t)R * (k % R));
    return (int)((bits[bit >> 6] >> (bit & 63)) & 1u);
}

void meso_voxels_free(meso_voxels* v)
{
    if (!v)
        return;
    free(v->tile_class);
    free(v->mixed_tiles);
    free(v->bits);
    memset(v, 0, sizeof(*v));
}
