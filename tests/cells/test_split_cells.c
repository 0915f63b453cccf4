/* Split cells (bake/split_cells.c) against references written independently
 * here, with zero mismatches allowed:
 *  - split cells: breadth-first flood fill, 26-neighbours, no wrap;
 *  - cells: flood fill on the torus (26-neighbours with wrap) that also lifts
 *    every voxel to a tile offset, so a cell reaching its own copy in another
 *    tile (wraps) is seen, and every split cell's offset is checked against
 *    the lifted one;
 *  - face codes: the thesis's own method, Algorithm 4.2 (OR over the 26
 *    same-index neighbours), ping-ponged until nothing changes;
 *  - numbering: contiguous ranges per cell, order, ranks, thesis slots.
 * On random Voronoi, sphere and noise maps and on hand-built cases (corner
 * cell → 8 split cells, interior cell, a ring touching one face twice, tubes
 * that wrap, a comb with 11 split cells, > 64 split cells refused for the
 * thesis packing). Prints timings at R = 64 and 128 (never asserted). */
#include "meso_clock.h"
#include "test_util.h"

#include <string.h>
#include <time.h>

#include "split_cells.h"


static size_t lin(uint32_t R, int64_t x, int64_t y, int64_t z)
{
    return (size_t)x + R * ((size_t)y + (size_t)R * (size_t)z);
}

static int64_t wrap(int64_t a, uint32_t R, int* w)
{
    *w = a < 0 ? -1 : a >= (int64_t)R ? 1 : 0;
    return a - (int64_t)*w * R;
}

/* >>references ------------------------------------------------------------- */

/* Component labels (1-based, 0 for empty) by BFS; with `torus`, neighbours
 * wrap and lift[3 v..] gets each voxel's tile offset from its component's
 * start, wraps[label] = 1 when some edge contradicts the lift. */
static uint32_t flood(const meso_tile_map* m, int torus, uint32_t* label, int32_t* lift, uint8_t* wraps)
{
    const uint32_t R = m->res;
    const size_t n = (size_t)R * R * R;
    uint32_t* queue = malloc(n * sizeof(uint32_t));
    memset(label, 0, n * sizeof(uint32_t));
    uint32_t count = 0;
    for (size_t s = 0; s < n; ++s) {
        if (!m->cells[s] || label[s])
            continue;
        ++count;
        if (wraps)
            wraps[count] = 0;
        size_t head = 0, tail = 0;
        queue[tail++] = (uint32_t)s;
        label[s] = count;
        if (lift)
            lift[3 * s] = lift[3 * s + 1] = lift[3 * s + 2] = 0;
        while (head < tail) {
            const size_t v = queue[head++];
            const int64_t x = (int64_t)(v % R), y = (int64_t)(v / R % R), z = (int64_t)(v / ((size_t)R * R));
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        if (!dx && !dy && !dz)
                            continue;
                        int w[3];
                        const int64_t qx = wrap(x + dx, R, &w[0]), qy = wrap(y + dy, R, &w[1]),
                                      qz = wrap(z + dz, R, &w[2]);
                        if (!torus && (w[0] || w[1] || w[2]))
                            continue;
                        const size_t q = lin(R, qx, qy, qz);
                        if (m->cells[q] != m->cells[v])
                            continue;
                        if (!label[q]) {
                            label[q] = count;
                            if (lift)
                                for (int a = 0; a < 3; ++a)
                                    lift[3 * q + a] = lift[3 * v + a] + w[a];
                            queue[tail++] = (uint32_t)q;
                        } else if (lift) {
                            for (int a = 0; a < 3; ++a)
                                if (lift[3 * q + a] != lift[3 * v + a] + w[a])
                                    wraps[count] = 1;
                        }
                    }
        }
    }
    free(queue);
    return count;
}

static uint8_t face_bits(int64_t x, int64_t y, int64_t z, uint32_t R)
{
    const int64_t h = (int64_t)R - 1;
    return (uint8_t)((x == 0) | (x == h) << 1 | (y == 0) << 2 | (y == h) << 3 | (z == 0) << 4 | (z == h) << 5);
}

/* Thesis Algorithm 4.1/4.2: ping-pong OR propagation until a fixpoint.
 * Returns the passes taken (the last one changes nothing). */
static uint32_t thesis_face_codes(const meso_tile_map* m, uint8_t* code)
{
    const uint32_t R = m->res;
    const size_t n = (size_t)R * R * R;
    uint8_t* next = malloc(n);
    for (size_t v = 0; v < n; ++v)
        code[v] = m->cells[v] ? face_bits((int64_t)(v % R), (int64_t)(v / R % R), (int64_t)(v / ((size_t)R * R)), R) : 0;
    uint32_t passes = 0;
    for (int changed = 1; changed;) {
        changed = 0;
        ++passes;
        for (size_t v = 0; v < n; ++v) {
            uint8_t c = code[v];
            if (m->cells[v]) {
                const int64_t x = (int64_t)(v % R), y = (int64_t)(v / R % R), z = (int64_t)(v / ((size_t)R * R));
                for (int dz = -1; dz <= 1; ++dz)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dx = -1; dx <= 1; ++dx) {
                            const int64_t qx = x + dx, qy = y + dy, qz = z + dz;
                            if (qx < 0 || qy < 0 || qz < 0 || qx >= R || qy >= R || qz >= R)
                                continue;
                            const size_t q = lin(R, qx, qy, qz);
                            if (m->cells[q] == m->cells[v])
                                c |= code[q];
                        }
            }
            next[v] = c;
            changed |= c != code[v];
        }
        memcpy(code, next, n);
    }
    free(next);
    return passes;
}

/* >>the check ---------------------------------------------------------------- */

typedef struct stats {
    size_t maps, voxels, mismatches;
    uint32_t max_passes;
} stats;

static stats total;

/* Computes the split cells of m and checks everything against the references.
 * Returns the result (caller frees) for case-specific assertions. */
static meso_split_cells check(const meso_tile_map* m, const char* name)
{
    const uint32_t R = m->res;
    const size_t n = (size_t)R * R * R;
    meso_split_cells sc;
    meso_error err;
    assert(meso_split_cells_compute(m, 1, &sc, &err) == MESO_OK);
    {
        meso_split_cells sc2;
        assert(meso_split_cells_compute(m, 2, &sc2, &err) == MESO_OK);
        assert(sc2.split_count == sc.split_count && sc2.cell_count == sc.cell_count);
        assert(memcmp(sc.voxel_split, sc2.voxel_split, n * sizeof(uint32_t)) == 0);
        assert(!sc.split_count || memcmp(sc.splits, sc2.splits, sc.split_count * sizeof(meso_split_cell)) == 0);
        meso_split_cells_free(&sc2);
    }
    uint32_t* lsplit = malloc(n * sizeof(uint32_t));
    uint32_t* lcell = malloc(n * sizeof(uint32_t));
    int32_t* lift = malloc(3 * n * sizeof(int32_t));
    uint8_t* wraps = malloc(n + 1);
    uint8_t* code = malloc(n);
    const uint32_t S = flood(m, 0, lsplit, NULL, NULL);
    const uint32_t C = flood(m, 1, lcell, lift, wraps);
    const uint32_t passes = thesis_face_codes(m, code);
    size_t bad = 0;
    bad += S != sc.split_count;
    bad += C != sc.cell_count;

    /* Bijections: reference split label <-> our split id, reference cell
     * label <-> our cell. Plus per-split sums recomputed from voxels. */
    uint32_t* ref_of_split = calloc(S + 2, sizeof(uint32_t));
    uint32_t* split_of_ref = calloc(S + 2, sizeof(uint32_t));
    uint32_t* ref_of_cell = calloc(C + 2, sizeof(uint32_t));
    uint32_t* cell_of_ref = calloc(C + 2, sizeof(uint32_t));
    uint32_t* count = calloc(S + 2, sizeof(uint32_t));
    uint32_t* first = malloc((S + 2) * sizeof(uint32_t));
    uint8_t* faces = calloc(S + 2, 1);
    int32_t* delta = malloc(3 * (C + 2) * sizeof(int32_t)); /* our offset - lift, per cell */
    uint8_t* delta_set = calloc(C + 2, 1);
    for (uint32_t s = 0; s < S + 2; ++s)
        first[s] = UINT32_MAX;
    for (size_t v = 0; v < n && bad == 0; ++v) {
        const uint32_t id = sc.voxel_split[v];
        if (!m->cells[v]) {
            bad += id != 0;
            continue;
        }
        if (id < 1 || id > S) {
            ++bad;
            continue;
        }
        const meso_split_cell* sp = &sc.splits[id - 1];
        if (!ref_of_split[id])
            ref_of_split[id] = lsplit[v];
        if (!split_of_ref[lsplit[v]])
            split_of_ref[lsplit[v]] = id;
        bad += ref_of_split[id] != lsplit[v] || split_of_ref[lsplit[v]] != id;
        const uint32_t c = sp->cell;
        if (c < 1 || c > C) {
            ++bad;
            continue;
        }
        if (!ref_of_cell[c])
            ref_of_cell[c] = lcell[v];
        if (!cell_of_ref[lcell[v]])
            cell_of_ref[lcell[v]] = c;
        bad += ref_of_cell[c] != lcell[v] || cell_of_ref[lcell[v]] != c;
        bad += sp->tile_index != m->cells[v];
        bad += sp->face_code != code[v]; /* the thesis's propagated code */
        count[id]++;
        if (first[id] == UINT32_MAX)
            first[id] = (uint32_t)v;
        faces[id] |= face_bits((int64_t)(v % R), (int64_t)(v / R % R), (int64_t)(v / ((size_t)R * R)), R);
        /* Wrapping and offsets: our wraps flag is the lifted flood's, and in
         * a bounded cell our offset minus the lift is one constant. */
        bad += sc.cells[c - 1].wraps != wraps[lcell[v]];
        if (!wraps[lcell[v]]) {
            if (!delta_set[c]) {
                delta_set[c] = 1;
                for (int a = 0; a < 3; ++a)
                    delta[3 * c + a] = sp->offset[a] - lift[3 * v + a];
            }
            for (int a = 0; a < 3; ++a)
                bad += delta[3 * c + a] != sp->offset[a] - lift[3 * v + a];
        }
    }
    /* Per split cell and per cell: sums, order, ranges, ranks, slots. */
    uint32_t wrapping = 0, max_per_cell = 0, next_split = 1;
    for (uint32_t c = 1; c <= sc.cell_count && bad == 0; ++c) {
        const meso_cell* cell = &sc.cells[c - 1];
        bad += cell->first_split != next_split || cell->split_count == 0;
        next_split += cell->split_count;
        wrapping += cell->wraps;
        if (cell->split_count > max_per_cell)
            max_per_cell = cell->split_count;
        uint64_t vox = 0;
        for (uint32_t r = 0; r < cell->split_count && bad == 0; ++r) {
            const uint32_t id = cell->first_split + r;
            const meso_split_cell* sp = &sc.splits[id - 1];
            bad += sp->cell != c || sp->rank != (r < 255 ? r : 255) || sp->thesis_slot != 8 * (c - 1) + r;
            bad += sp->voxel_count != count[id] || sp->first_voxel != first[id] || sp->face_code != faces[id];
            bad += sp->tile_index != cell->tile_index;
            vox += sp->voxel_count;
            if (r > 0) { /* ascending (face code, first voxel) */
                const meso_split_cell* pr = sp - 1;
                bad += pr->face_code > sp->face_code ||
                       (pr->face_code == sp->face_code && pr->first_voxel >= sp->first_voxel);
            }
        }
        bad += vox != cell->voxel_count;
        /* The cell's first split cell in scan order is the offset origin. */
        uint32_t first_id = cell->first_split;
        for (uint32_t r = 0; r < cell->split_count; ++r)
            if (sc.splits[cell->first_split + r - 1].first_voxel < sc.splits[first_id - 1].first_voxel)
                first_id = cell->first_split + r;
        const int32_t* o = sc.splits[first_id - 1].offset;
        bad += o[0] != 0 || o[1] != 0 || o[2] != 0;
        if (c > 1) { /* cells ascending by (tile index, first voxel) */
            const meso_cell* pc = cell - 1;
            uint32_t f0 = UINT32_MAX, f1 = UINT32_MAX;
            for (uint32_t r = 0; r < pc->split_count; ++r)
                if (sc.splits[pc->first_split + r - 1].first_voxel < f0)
                    f0 = sc.splits[pc->first_split + r - 1].first_voxel;
            for (uint32_t r = 0; r < cell->split_count; ++r)
                if (sc.splits[cell->first_split + r - 1].first_voxel < f1)
                    f1 = sc.splits[cell->first_split + r - 1].first_voxel;
            bad += pc->tile_index > cell->tile_index || (pc->tile_index == cell->tile_index && f0 >= f1);
        }
    }
    bad += next_split != sc.split_count + 1;
    bad += wrapping != sc.wrapping_cells || max_per_cell != sc.max_splits_per_cell;

    fprintf(stderr, "    %-28s R=%-3u S=%-4u C=%-4u max/cell=%-3u wrapping=%-3u packing=%d thesis passes=%-3u mismatches=%zu\n",
            name, R, sc.split_count, sc.cell_count, sc.max_splits_per_cell, sc.wrapping_cells,
            (int)meso_split_cells_packing(&sc), passes, bad);
    assert(bad == 0);
    total.maps++;
    total.voxels += n;
    total.mismatches += bad;
    if (passes > total.max_passes)
        total.max_passes = passes;
    free(lsplit);
    free(lcell);
    free(lift);
    free(wraps);
    free(code);
    free(ref_of_split);
    free(split_of_ref);
    free(ref_of_cell);
    free(cell_of_ref);
    free(count);
    free(first);
    free(faces);
    free(delta);
    free(delta_set);
    return sc;
}

/* >>maps ---------------------------------------------------------------------- */

static meso_tile_map empty_map(uint32_t R)
{
    meso_tile_map m = {.kind = MESO_TILE_MAP_RAW, .res = R, .cell_count = 1};
    m.cells = calloc((size_t)R * R * R, sizeof(uint16_t));
    return m;
}

/* Torus distance² (voxel units) from voxel centre (x, y, z) to point c. */
static double torus_d2(uint32_t R, uint32_t x, uint32_t y, uint32_t z, const double c[3])
{
    const double p[3] = {x + 0.5, y + 0.5, z + 0.5};
    double d2 = 0;
    for (int a = 0; a < 3; ++a) {
        double d = fabs(p[a] - c[a]);
        d = fmod(d, (double)R);
        if (d > R - d)
            d = R - d;
        d2 += d * d;
    }
    return d2;
}

static void random_maps_match_references(void)
{
    uint64_t rng = 2024;
    for (int i = 0; i < 14; ++i) {
        const uint32_t R = 8 + (uint32_t)(test_rng_next(&rng) % 17);  /* 8..24 */
        const uint32_t K = 2 + (uint32_t)(test_rng_next(&rng) % 11);  /* 2..12 */
        meso_tile_map m;
        meso_error err;
        const meso_tile_map_params p = {i % 2 ? MESO_TILE_MAP_SPHERES : MESO_TILE_MAP_VORONOI, R, K,
                                        0.1 + 0.3 * test_rng_uniform(&rng, 0, 1), test_rng_next(&rng)};
        assert(meso_tile_map_generate(&p, 1, &m, &err) == MESO_OK);
        char name[64];
        snprintf(name, sizeof(name), "%s K=%u", i % 2 ? "spheres" : "voronoi", K);
        meso_split_cells sc = check(&m, name);
        if (p.kind == MESO_TILE_MAP_VORONOI) { /* at most 8 pieces, one cell per index */
            assert(sc.max_splits_per_cell <= 8 && sc.cell_count == K);
            for (uint32_t c = 0; c < sc.cell_count; ++c)
                assert(sc.cells[c].tile_index == c + 1);
        }
        meso_split_cells_free(&sc);
        meso_tile_map_free(&m);
    }
    /* Noise: many tiny, tangled and wrapping components (raw maps). */
    for (int i = 0; i < 10; ++i) {
        const uint32_t R = 5 + (uint32_t)(test_rng_next(&rng) % 10);
        const uint32_t values = 1 + (uint32_t)(test_rng_next(&rng) % 3);
        const double p_empty = test_rng_uniform(&rng, 0.2, 0.8);
        meso_tile_map m = empty_map(R);
        for (size_t v = 0; v < (size_t)R * R * R; ++v)
            m.cells[v] = test_rng_uniform(&rng, 0, 1) < p_empty ? 0 : (uint16_t)(1 + test_rng_next(&rng) % values);
        char name[64];
        snprintf(name, sizeof(name), "noise %u values p0=%.2f", values, p_empty);
        meso_split_cells sc = check(&m, name);
        meso_split_cells_free(&sc);
        meso_tile_map_free(&m);
    }
    /* One larger Voronoi map. */
    meso_tile_map m;
    meso_error err;
    assert(meso_tile_map_generate(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, 40, 10, 0, 77}, 1, &m, &err) ==
           MESO_OK);
    meso_split_cells sc = check(&m, "voronoi K=10");
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
}

static void corner_cell_has_eight_split_cells(void)
{
    const uint32_t R = 16;
    meso_tile_map m = empty_map(R);
    const double corner[3] = {0, 0, 0};
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x)
                m.cells[lin(R, x, y, z)] = torus_d2(R, x, y, z, corner) <= 4.5 * 4.5;
    meso_split_cells sc = check(&m, "corner ball");
    assert(sc.split_count == 8 && sc.cell_count == 1 && sc.wrapping_cells == 0);
    uint32_t codes = 0;
    for (uint32_t s = 0; s < 8; ++s) {
        const meso_split_cell* sp = &sc.splits[s];
        const uint8_t f = sp->face_code;
        /* one face per axis */
        assert(((f & 3) == 1 || (f & 3) == 2) && ((f >> 2 & 3) == 1 || (f >> 2 & 3) == 2) &&
               ((f >> 4 & 3) == 1 || (f >> 4 & 3) == 2));
        codes |= 1u << ((f & 2) >> 1 | (f & 8) >> 2 | (f & 32) >> 3);
        /* In one copy, the piece at x = R-1 sits one tile towards -x of the
         * piece at x = 0 (the first split cell, at the origin voxel). */
        assert(sp->offset[0] == ((f & MESO_FACE_X1) ? -1 : 0));
        assert(sp->offset[1] == ((f & MESO_FACE_Y1) ? -1 : 0));
        assert(sp->offset[2] == ((f & MESO_FACE_Z1) ? -1 : 0));
        assert(sp->thesis_slot == s);
    }
    assert(codes == 0xFF);
    assert(meso_split_cells_packing(&sc) == MESO_SPLIT_PACK_THESIS);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
}

static void interior_cell_has_face_code_zero(void)
{
    const uint32_t R = 12;
    meso_tile_map m = empty_map(R);
    const double c[3] = {6, 6, 6};
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x)
                m.cells[lin(R, x, y, z)] = torus_d2(R, x, y, z, c) <= 9.0 ? 3 : 0;
    meso_split_cells sc = check(&m, "interior ball");
    assert(sc.split_count == 1 && sc.cell_count == 1 && sc.splits[0].face_code == 0 && !sc.cells[0].wraps);
    assert(sc.splits[0].tile_index == 3 && sc.cells[0].tile_index == 3);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
}

static void ring_touches_one_face_twice(void)
{
    /* A ring in the plane z = R/2 centred on the face x = 0: each half is
     * one split cell touching its face in two separate places. */
    const uint32_t R = 24;
    meso_tile_map m = empty_map(R);
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                double dx = x + 0.5;
                if (dx > R / 2.0)
                    dx -= R;
                const double dy = y + 0.5 - R / 2.0, dz = z + 0.5 - R / 2.0;
                const double t = sqrt(dx * dx + dy * dy) - R / 4.0;
                m.cells[lin(R, x, y, z)] = t * t + dz * dz <= 1.6 * 1.6;
            }
    meso_split_cells sc = check(&m, "ring across x = 0");
    assert(sc.split_count == 2 && sc.cell_count == 1 && sc.wrapping_cells == 0);
    assert(sc.splits[0].face_code == MESO_FACE_X0 && sc.splits[1].face_code == MESO_FACE_X1);
    assert(sc.splits[1].offset[0] - sc.splits[0].offset[0] == -1);
    /* The x = 0 face holds two separate patches of the same split cell. */
    uint32_t patches = 0;
    for (uint32_t y = 1; y < R; ++y) {
        int in0 = 0, in1 = 0;
        for (uint32_t z = 0; z < R; ++z) {
            in0 |= m.cells[lin(R, 0, y - 1, z)] != 0;
            in1 |= m.cells[lin(R, 0, y, z)] != 0;
        }
        patches += !in0 && in1;
    }
    assert(patches == 2);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
}

static void wrapping_cells_are_reported(void)
{
    const uint32_t R = 12;
    /* A straight tube along x: one split cell on both x faces, infinite. */
    meso_tile_map m = empty_map(R);
    for (uint32_t x = 0; x < R; ++x)
        for (uint32_t d = 0; d < 4; ++d)
            m.cells[lin(R, x, 5 + d % 2, 5 + d / 2)] = 1;
    meso_split_cells sc = check(&m, "tube along x");
    assert(sc.split_count == 1 && sc.splits[0].face_code == (MESO_FACE_X0 | MESO_FACE_X1) && sc.cells[0].wraps);
    meso_split_cells_free(&sc);
    /* A diagonal tube: leaves through +x and +y, back through -x and -y. */
    memset(m.cells, 0, (size_t)R * R * R * sizeof(uint16_t));
    for (uint32_t x = 0; x < R; ++x)
        for (uint32_t z = 5; z < 7; ++z) {
            m.cells[lin(R, x, x, z)] = 2;
            m.cells[lin(R, x, (x + 1) % R, z)] = 2;
        }
    sc = check(&m, "diagonal tube");
    assert(sc.cell_count == 1 && sc.cells[0].wraps && sc.wrapping_cells == 1);
    meso_split_cells_free(&sc);
    /* K = 1 Voronoi and a full 1-voxel tile: everything, wrapping. */
    memset(m.cells, 0, (size_t)R * R * R * sizeof(uint16_t));
    for (size_t v = 0; v < (size_t)R * R * R; ++v)
        m.cells[v] = 1;
    sc = check(&m, "full tile");
    assert(sc.split_count == 1 && sc.splits[0].face_code == 63 && sc.cells[0].wraps);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
    m = empty_map(1);
    m.cells[0] = 9;
    sc = check(&m, "R = 1");
    assert(sc.split_count == 1 && sc.splits[0].face_code == 63 && sc.cells[0].wraps);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
    /* Empty tile. */
    m = empty_map(6);
    sc = check(&m, "empty tile");
    assert(sc.split_count == 0 && sc.cell_count == 0 && meso_split_cells_packing(&sc) == MESO_SPLIT_PACK_THESIS);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
}

static void comb_cell_has_eleven_split_cells(void)
{
    /* A slab at x = R-1 and ten fingers at x = 0..2 that reach it only
     * through the border: one cell, 11 split cells (> 8: not the thesis's). */
    const uint32_t R = 16;
    meso_tile_map m = empty_map(R);
    for (uint32_t z = 1; z < R - 1; ++z) /* not the whole face: that plane would wrap */
        for (uint32_t y = 1; y < R - 1; ++y)
            m.cells[lin(R, R - 1, y, z)] = 4;
    for (uint32_t f = 0; f < 10; ++f)
        for (uint32_t x = 0; x < 3; ++x)
            m.cells[lin(R, x, 2 + 3 * (f % 4), 2 + 4 * (f / 4))] = 4;
    meso_split_cells sc = check(&m, "comb");
    assert(sc.split_count == 11 && sc.cell_count == 1 && sc.max_splits_per_cell == 11 && !sc.cells[0].wraps);
    for (uint32_t s = 0; s < 10; ++s)
        assert(sc.splits[s].face_code == MESO_FACE_X0 && sc.splits[s].rank == s);
    assert(sc.splits[10].face_code == MESO_FACE_X1 && sc.splits[10].thesis_slot == 10);
    assert(meso_split_cells_packing(&sc) == MESO_SPLIT_PACK_DENSE64);
    meso_error err;
    assert(meso_split_cells_check_packing(&sc, MESO_SPLIT_PACK_THESIS, &err) == MESO_ERR_INVALID_ARG);
    assert(err.code == MESO_TILEMAP_ISSUE_PACKING);
    fprintf(stderr, "    E%u %s\n", err.code, err.message);
    assert(meso_split_cells_check_packing(&sc, MESO_SPLIT_PACK_DENSE64, &err) == MESO_OK);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
}

static void more_than_64_split_cells_do_not_fit(void)
{
    /* 5 × 5 × 5 separate voxels of one index: 125 cells (each its own), and
     * Voronoi with 20 seeds (> 8 cells). */
    const uint32_t R = 15;
    meso_tile_map m = empty_map(R);
    for (uint32_t z = 1; z < R; z += 3)
        for (uint32_t y = 1; y < R; y += 3)
            for (uint32_t x = 1; x < R; x += 3)
                m.cells[lin(R, x, y, z)] = 1;
    meso_split_cells sc = check(&m, "125 dots");
    assert(sc.split_count == 125 && sc.cell_count == 125 && sc.max_splits_per_cell == 1);
    assert(meso_split_cells_packing(&sc) == MESO_SPLIT_PACK_WIDE);
    meso_error err;
    assert(meso_split_cells_check_packing(&sc, MESO_SPLIT_PACK_THESIS, &err) == MESO_ERR_INVALID_ARG);
    assert(err.code == MESO_TILEMAP_ISSUE_PACKING && strstr(err.message, "125 split cells"));
    fprintf(stderr, "    E%u %s\n", err.code, err.message);
    assert(meso_split_cells_check_packing(&sc, MESO_SPLIT_PACK_DENSE64, &err) == MESO_ERR_INVALID_ARG);
    fprintf(stderr, "    E%u %s\n", err.code, err.message);
    assert(meso_split_cells_check_packing(&sc, MESO_SPLIT_PACK_WIDE, &err) == MESO_OK);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);

    assert(meso_tile_map_generate(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, 24, 20, 0, 5}, 1, &m, &err) ==
           MESO_OK);
    sc = check(&m, "voronoi K=20");
    assert(sc.cell_count == 20 && meso_split_cells_packing(&sc) != MESO_SPLIT_PACK_THESIS);
    assert(meso_split_cells_check_packing(&sc, MESO_SPLIT_PACK_THESIS, &err) == MESO_ERR_INVALID_ARG);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);

    /* And the thesis's own setup fits: 8 seeds (its Fig. 3.2). */
    assert(meso_tile_map_generate(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, 32, 8, 0, 3}, 1, &m, &err) ==
           MESO_OK);
    sc = check(&m, "voronoi K=8");
    assert(sc.cell_count == 8 && meso_split_cells_check_packing(&sc, MESO_SPLIT_PACK_THESIS, &err) == MESO_OK);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&m);
}

/* How often a generated Voronoi cell touches its own periodic copy (it then
 * wraps: its region reaches the bisector between its seed and the seed's
 * image, or a voxel of it is a 26-neighbour of one of its copy's). Printed
 * for the membership stage to decide on; asserted only to be exact above. */
static void voronoi_self_contact_rate(void)
{
    const uint32_t counts[] = {2, 4, 8, 16, 32, 64};
    for (size_t j = 0; j < sizeof(counts) / sizeof(counts[0]); ++j) {
        uint32_t cells = 0, wrapping = 0, fits = 0;
        for (uint64_t seed = 1; seed <= 8; ++seed) {
            meso_tile_map m;
            meso_split_cells sc;
            meso_error err;
            assert(meso_tile_map_generate(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, 32, counts[j], 0, seed}, 1,
                                          &m, &err) == MESO_OK);
            assert(meso_split_cells_compute(&m, 1, &sc, &err) == MESO_OK);
            cells += sc.cell_count;
            wrapping += sc.wrapping_cells;
            fits += meso_split_cells_packing(&sc) == MESO_SPLIT_PACK_THESIS;
            meso_split_cells_free(&sc);
            meso_tile_map_free(&m);
        }
        fprintf(stderr, "    voronoi R=32 K=%-2u, 8 seeds: %u of %u cells wrap (%.0f%%); %u of 8 tiles fit the thesis packing\n",
                counts[j], wrapping, cells, 100.0 * wrapping / cells, fits);
    }
}

static void timings(void)
{
    const uint32_t res[] = {64, 128};
    const uint32_t counts[] = {8, 64};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2; ++j) {
            meso_tile_map m;
            meso_split_cells sc;
            meso_error err;
            const double t0 = meso_seconds();
            assert(meso_tile_map_generate(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, res[i], counts[j], 0, 1}, 1,
                                          &m, &err) == MESO_OK);
            const double t1 = meso_seconds();
            assert(meso_split_cells_compute(&m, 1, &sc, &err) == MESO_OK);
            const double t2 = meso_seconds();
            fprintf(stderr, "    timing voronoi R=%u K=%u (1 thread): tile map %.3f s, split cells %.3f s; S=%u C=%u max/cell=%u\n",
                    res[i], counts[j], t1 - t0, t2 - t1, sc.split_count, sc.cell_count, sc.max_splits_per_cell);
            meso_split_cells_free(&sc);
            meso_tile_map_free(&m);
        }
}

int main(void)
{
    TEST_RUN(corner_cell_has_eight_split_cells);
    TEST_RUN(interior_cell_has_face_code_zero);
    TEST_RUN(ring_touches_one_face_twice);
    TEST_RUN(wrapping_cells_are_reported);
    TEST_RUN(comb_cell_has_eleven_split_cells);
    TEST_RUN(more_than_64_split_cells_do_not_fit);
    TEST_RUN(random_maps_match_references);
    TEST_RUN(voronoi_self_contact_rate);
    TEST_RUN(timings);
    fprintf(stderr, "test_split_cells: %zu maps, %zu voxels, %zu mismatches; the thesis's propagation took up to %u passes\n",
            total.maps, total.voxels, total.mismatches, total.max_passes);
    return 0;
}
