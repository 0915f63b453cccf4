/* Membership maps (bake/membership.c) against a brute force written
 * independently here, zero mismatches allowed:
 *  - a dense inside/outside grid of every voxel centre, from CGAL's exact
 *    point-in-mesh (closed meshes) or the analytic cube (the open cube), and
 *    checked against the sparse voxelization on the way;
 *  - pre-merge tags per (tile, split cell) from the dense grid;
 *  - non-wrapping cells: copies found by a flood fill over VOXELS in object
 *    space (26-neighbours of the same tile-map index across tile borders, in
 *    the grid grown by a margin of outside tiles), no split-cell offsets
 *    used; each copy's tag combines its voxels (Table 4.2);
 *  - wrapping cells: the rule of membership.h (pieces as the offsets define
 *    them), evaluated by a naive loop over every (tile, split cell);
 *  - every tag of every split cell of every tile, every tile class, the cell
 *    counts of the report; 1 = 2 threads; streamed = from kept voxels;
 *  - on Voronoi and sphere tile maps (R 8..16, 4..8 tiles per axis), with
 *    wrapping cells from 0 % to 100 %, on closed meshes and the open cube.
 * Prints sizes against the thesis's 16 bytes per tile. */
#include "test_util.h"

#include <string.h>

#include "adapters.h"
#include "membership.h"

static meso_mesh load(const char* name)
{
    meso_mesh m;
    meso_error err = {0};
    assert(meso_openmesh_read(test_data(name), &m, NULL, &err) == MESO_OK);
    return m;
}

/* >>dense reference --------------------------------------------------------- */

typedef struct dense {
    uint32_t N, R, T;
    uint8_t* inside; /* N^3, x fastest */
} dense;

/* Every centre: CGAL for closed meshes (`cube` = 0), else the analytic cube
 * [-1, 1]^3 (no centre of a fitted grid lies on its faces). Checked against
 * the voxelization `v`; centres CGAL puts on the surface take v's answer. */
static dense dense_reference(const meso_mesh* m, const meso_voxels* v, int cube)
{
    const meso_voxel_grid* g = &v->grid;
    dense d = {g->tiles[0] * g->tile_res, g->tile_res, g->tiles[0], NULL};
    const size_t n = (size_t)d.N * d.N * d.N;
    d.inside = malloc(n);
    double* p = malloc(sizeof(double) * 3 * n);
    assert(d.inside && p);
    for (uint32_t k = 0; k < d.N; ++k)
        for (uint32_t j = 0; j < d.N; ++j)
            for (uint32_t i = 0; i < d.N; ++i)
                meso_voxel_center(g, i, j, k, p + 3 * (i + (size_t)d.N * (j + (size_t)d.N * k)));
    size_t on = 0, differ = 0;
    if (cube) {
        for (size_t i = 0; i < n; ++i)
            d.inside[i] = fabs(p[3 * i]) < 1 && fabs(p[3 * i + 1]) < 1 && fabs(p[3 * i + 2]) < 1;
    } else {
#if MESO_HAVE_CGAL
        meso_error err = {0};
        meso_cgal_inside* cg = NULL;
        int8_t* side = malloc(n);
        assert(side && meso_cgal_inside_create(m, &cg, &err) == MESO_OK);
        assert(meso_cgal_inside_query(cg, p, n, side, &err) == MESO_OK);
        for (size_t i = 0; i < n; ++i) {
            on += side[i] == 0;
            d.inside[i] = side[i] > 0;
        }
        meso_cgal_inside_destroy(cg);
        free(side);
#else
        (void)m;
        assert(!"needs CGAL");
#endif
    }
    for (uint32_t k = 0; k < d.N; ++k)
        for (uint32_t j = 0; j < d.N; ++j)
            for (uint32_t i = 0; i < d.N; ++i) {
                const size_t x = i + (size_t)d.N * (j + (size_t)d.N * k);
                const int mine = meso_voxels_inside(v, i, j, k);
                if (!cube && d.inside[x] != mine)
                    differ++;
                d.inside[x] = (uint8_t)mine; /* equal but for centres on the surface (counted) */
            }
    assert(differ <= on);
    free(p);
    return d;
}

/* Reference tags: refs[t S + s - 1] for tile t (x fastest), split s. */
typedef struct reference {
    uint8_t* tags;
    uint64_t cells[3];
} reference;

static uint64_t tile_id(const dense* d, int64_t tx, int64_t ty, int64_t tz)
{
    return (uint64_t)tx + d->T * ((uint64_t)ty + (uint64_t)d->T * (uint64_t)tz);
}

static reference brute_force(const dense* d, const meso_tile_map* map, const meso_split_cells* sc)
{
    const uint32_t R = d->R, T = d->T, N = d->N, S = sc->split_count;
    const uint64_t tiles = (uint64_t)T * T * T;
    reference ref = {calloc(tiles * S + 1, 1), {0, 0, 0}};
    /* pre-merge tags: bit 1 inside seen, bit 2 outside seen */
    uint8_t* seen = calloc(tiles * S + 1, 1);
    assert(ref.tags && seen);
    for (uint32_t k = 0; k < N; ++k)
        for (uint32_t j = 0; j < N; ++j)
            for (uint32_t i = 0; i < N; ++i) {
                const uint32_t s = sc->voxel_split[i % R + R * (j % R + R * (k % R))];
                if (s)
                    seen[tile_id(d, i / R, j / R, k / R) * S + s - 1] |=
                        d->inside[i + (size_t)N * (j + (size_t)N * k)] ? 1 : 2;
            }
    /* non-wrapping cells: flood over voxels in object space, grid grown by M
     * tiles of outside voxels on every side */
    int32_t M = 1;
    for (uint32_t s = 0; s < S; ++s)
        for (int a = 0; a < 3; ++a)
            if (!sc->cells[sc->splits[s].cell - 1].wraps && abs(sc->splits[s].offset[a]) + 1 > M)
                M = abs(sc->splits[s].offset[a]) + 1;
    const int64_t E = (int64_t)(T + 2 * (uint32_t)M) * R, off = (int64_t)M * R;
    const size_t ne = (size_t)E * E * E;
    uint32_t* label = calloc(ne, sizeof(uint32_t));
    uint32_t* queue = malloc(ne * sizeof(uint32_t));
    uint8_t* comp = malloc(ne + 1); /* tag per component */
    assert(label && queue && comp);
    uint32_t ncomp = 0;
    for (size_t v0 = 0; v0 < ne; ++v0) {
        const int64_t x0 = (int64_t)(v0 % (size_t)E), y0 = (int64_t)(v0 / (size_t)E % (size_t)E),
                      z0 = (int64_t)(v0 / (size_t)E / (size_t)E);
        const uint32_t lv = (uint32_t)(x0 % R + R * (y0 % R + R * (z0 % R)));
        const uint32_t s0 = sc->voxel_split[lv];
        if (!s0 || label[v0] || sc->cells[sc->splits[s0 - 1].cell - 1].wraps)
            continue;
        const uint16_t index = map->cells[lv];
        label[v0] = ++ncomp;
        uint8_t tag = 0;
        size_t head = 0, tail = 0;
        queue[tail++] = (uint32_t)v0;
        while (head < tail) {
            const size_t v = queue[head++];
            const int64_t x = (int64_t)(v % (size_t)E), y = (int64_t)(v / (size_t)E % (size_t)E),
                          z = (int64_t)(v / (size_t)E / (size_t)E);
            const int64_t gx = x - off, gy = y - off, gz = z - off; /* grid voxel */
            const int in_grid = gx >= 0 && gy >= 0 && gz >= 0 && gx < N && gy < N && gz < N;
            tag |= in_grid && d->inside[gx + (size_t)N * (gy + (size_t)N * gz)] ? 1 : 2;
            for (int dz = -1; dz <= 1; ++dz)
                for (int dy = -1; dy <= 1; ++dy)
                    for (int dx = -1; dx <= 1; ++dx) {
                        const int64_t a = x + dx, b = y + dy, c = z + dz;
                        if (a < 0 || b < 0 || c < 0 || a >= E || b >= E || c >= E)
                            continue;
                        const size_t u = (size_t)a + (size_t)E * ((size_t)b + (size_t)E * (size_t)c);
                        if (label[u] || map->cells[a % R + R * (b % R + R * (c % R))] != index)
                            continue;
                        label[u] = ncomp;
                        queue[tail++] = (uint32_t)u;
                    }
        }
        comp[ncomp] = tag == 3 ? MESO_MEMB_INTERSECTED : tag == 1 ? MESO_MEMB_INSIDE : MESO_MEMB_OUTSIDE;
        /* count the copy when it reaches the grid */
        int reaches = 0;
        for (size_t q = 0; q < tail && !reaches; ++q) {
            const int64_t x = (int64_t)(queue[q] % (size_t)E) - off, y = (int64_t)(queue[q] / (size_t)E % (size_t)E) - off,
                          z = (int64_t)(queue[q] / (size_t)E / (size_t)E) - off;
            reaches = x >= 0 && y >= 0 && z >= 0 && x < N && y < N && z < N;
        }
        if (reaches)
            ref.cells[comp[ncomp]]++;
    }
    for (uint64_t t = 0; t < tiles; ++t) {
        const int64_t tx = (int64_t)(t % T), ty = (int64_t)(t / T % T), tz = (int64_t)(t / T / T);
        for (uint32_t s = 1; s <= S; ++s) {
            const meso_split_cell* sp = &sc->splits[s - 1];
            const meso_cell* cell = &sc->cells[sp->cell - 1];
            if (!cell->wraps) { /* the component of the split cell's first voxel in this tile */
                const int64_t fx = sp->first_voxel % R, fy = sp->first_voxel / R % R, fz = sp->first_voxel / R / R;
                const size_t u = (size_t)(off + tx * R + fx) +
                                 (size_t)E * ((size_t)(off + ty * R + fy) + (size_t)E * (size_t)(off + tz * R + fz));
                ref.tags[t * S + s - 1] = comp[label[u]];
                continue;
            }
            /* wrapping: the piece anchored at t - offset(s) */
            uint8_t acc = 0;
            int first_in_grid = 1;
            for (uint32_t b = cell->first_split; b < cell->first_split + cell->split_count; ++b) {
                const int32_t* ob = sc->splits[b - 1].offset;
                const int64_t ux = tx - sp->offset[0] + ob[0], uy = ty - sp->offset[1] + ob[1],
                              uz = tz - sp->offset[2] + ob[2];
                const int in = ux >= 0 && uy >= 0 && uz >= 0 && ux < T && uy < T && uz < T;
                acc |= in ? seen[tile_id(d, ux, uy, uz) * S + b - 1] : 2;
                if (in && b < s)
                    first_in_grid = 0;
            }
            const uint8_t tag = acc == 3 ? MESO_MEMB_INTERSECTED : acc == 1 ? MESO_MEMB_INSIDE : MESO_MEMB_OUTSIDE;
            ref.tags[t * S + s - 1] = tag;
            if (first_in_grid)
                ref.cells[tag]++;
        }
    }
    free(label);
    free(queue);
    free(comp);
    free(seen);
    return ref;
}

static void make_cells(meso_tile_map_params p, meso_tile_map* map, meso_split_cells* sc)
{
    meso_error err = {0};
    assert(meso_tile_map_generate(&p, 1, map, &err) == MESO_OK);
    assert(meso_split_cells_compute(map, 1, sc, &err) == MESO_OK);
}

/* >>cases --------------------------------------------------------------------- */

typedef struct config {
    const char* mesh;     /* tests/data name; "cube" = the open cube */
    meso_tile_map_kind kind;
    uint32_t res, count, tiles;
    double radius;
    uint64_t seed;
} config;

static void same_map(const meso_membership* a, const meso_membership* b)
{
    const uint64_t words = (a->tile_count + 15) / 16;
    assert(a->tile_count == b->tile_count && a->record_count == b->record_count);
    assert(memcmp(a->classes, b->classes, words * 4) == 0 && memcmp(a->rank, b->rank, words * 4) == 0);
    assert(memcmp(a->records, b->records, a->record_count * a->words_per_tile * 4) == 0);
    assert(a->cells_inside == b->cells_inside && a->cells_outside == b->cells_outside &&
           a->cells_intersected == b->cells_intersected && a->wrapping_copies == b->wrapping_copies);
}

static void check_config(const config* c)
{
    meso_error err = {0};
    meso_tile_map map;
    meso_split_cells sc;
    make_cells((meso_tile_map_params){c->kind, c->res, c->count, c->radius, c->seed}, &map, &sc);
    const int cube = strcmp(c->mesh, "cube") == 0;
    meso_mesh m = load(cube ? "cube_no_bottom.obj" : c->mesh);
    meso_voxel_grid g;
    assert(meso_voxel_grid_fit(&m, c->tiles, c->res, 1.0, &g, &err) == MESO_OK);
    meso_voxels v;
    assert(meso_voxelize(&m, &g, MESO_VOXELIZE_AUTO, 0, &v, &err) == MESO_OK);
    const dense d = dense_reference(&m, &v, cube);
    const reference ref = brute_force(&d, &map, &sc);

    meso_membership mb, mb1, mbv;
    assert(meso_membership_compute(&m, &g, &sc, MESO_VOXELIZE_AUTO, 2, &mb, &err) == MESO_OK);
    assert(meso_membership_compute(&m, &g, &sc, MESO_VOXELIZE_AUTO, 1, &mb1, &err) == MESO_OK);
    assert(meso_membership_from_voxels(&v, &sc, 0, &mbv, &err) == MESO_OK);
    same_map(&mb, &mb1);
    same_map(&mb, &mbv);

    const uint32_t T = c->tiles, S = sc.split_count;
    uint64_t wrong = 0, wrong_class = 0, tags[3] = {0, 0, 0};
    for (uint32_t tz = 0; tz < T; ++tz)
        for (uint32_t ty = 0; ty < T; ++ty)
            for (uint32_t tx = 0; tx < T; ++tx) {
                const uint64_t t = tx + (uint64_t)T * (ty + (uint64_t)T * tz);
                int all_in = 1, all_out = 1;
                for (uint32_t s = 1; s <= S; ++s) {
                    const uint8_t want = ref.tags[t * S + s - 1];
                    const meso_memb_tag got = meso_membership_get(&mb, tx, ty, tz, s);
                    if (got != want && wrong++ < 5)
                        fprintf(stderr, "      tile (%u %u %u) split %u (cell %u%s): %d, brute force %d\n", tx, ty,
                                tz, s, sc.splits[s - 1].cell, sc.cells[sc.splits[s - 1].cell - 1].wraps ? ", wraps" : "",
                                got, want);
                    tags[want]++;
                    all_in &= want == MESO_MEMB_INSIDE;
                    all_out &= want == MESO_MEMB_OUTSIDE;
                }
                const meso_tile_class want_class =
                    all_out ? MESO_TILE_OUTSIDE : all_in ? MESO_TILE_INSIDE : MESO_TILE_MIXED;
                wrong_class += meso_membership_tile(&mb, tx, ty, tz) != want_class;
            }
    const double thesis = 16.0 * (double)mb.tile_count;
    fprintf(stderr,
            "    %-8s %s R=%-2u K=%-2u %u^3 tiles: %u split cells, %u cells (%u wrap); tiles out/in/mixed "
            "%llu/%llu/%llu (%llu changed by the merge); split tags in/out/x %llu/%llu/%llu; cells in/out/x "
            "%llu/%llu/%llu (%llu wrapping pieces); %llu bytes (thesis %.0f); %llu wrong tags, %llu wrong classes\n",
            c->mesh, c->kind == MESO_TILE_MAP_VORONOI ? "voronoi" : "spheres", c->res, c->count, T, S, sc.cell_count,
            sc.wrapping_cells, (unsigned long long)mb.tiles_outside, (unsigned long long)mb.tiles_inside,
            (unsigned long long)mb.tiles_mixed, (unsigned long long)mb.tiles_merge_changed,
            (unsigned long long)tags[1], (unsigned long long)tags[0], (unsigned long long)tags[2],
            (unsigned long long)mb.cells_inside, (unsigned long long)mb.cells_outside,
            (unsigned long long)mb.cells_intersected, (unsigned long long)mb.wrapping_copies,
            (unsigned long long)mb.bytes, thesis, (unsigned long long)wrong, (unsigned long long)wrong_class);
    assert(wrong == 0 && wrong_class == 0);
    assert(mb.cells_inside == ref.cells[MESO_MEMB_INSIDE] && mb.cells_outside == ref.cells[MESO_MEMB_OUTSIDE] &&
           mb.cells_intersected == ref.cells[MESO_MEMB_INTERSECTED]);
    assert(tags[MESO_MEMB_INSIDE] > 0 && tags[MESO_MEMB_INTERSECTED] > 0); /* the cases exercise the merge */
    assert(mb.tiles_outside + mb.tiles_inside + mb.tiles_mixed == mb.tile_count);

    free(ref.tags);
    free(d.inside);
    meso_membership_free(&mb);
    meso_membership_free(&mb1);
    meso_membership_free(&mbv);
    meso_voxels_free(&v);
    meso_mesh_free(&m);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&map);
}

static void membership_matches_brute_force(void)
{
    static const config cases[] = {
        {"sphere.obj", MESO_TILE_MAP_VORONOI, 8, 8, 8, 0, 1},                /* the thesis's 8 seeds */
        {"torus.obj", MESO_TILE_MAP_VORONOI, 12, 16, 6, 0, 2},               /* no wrapping */
        {"spot_low_resolution.obj", MESO_TILE_MAP_VORONOI, 16, 4, 4, 0, 3}, /* most cells wrap */
        {"sphere.obj", MESO_TILE_MAP_VORONOI, 8, 2, 8, 0, 4},                /* every cell wraps */
        {"spot_low_resolution.obj", MESO_TILE_MAP_SPHERES, 16, 6, 6, 0.3, 5},
        {"wingnut.obj", MESO_TILE_MAP_SPHERES, 8, 3, 8, 0.45, 6},
        {"cube", MESO_TILE_MAP_VORONOI, 8, 12, 8, 0, 7}, /* open mesh: the winding path */
        {"sphere.obj", MESO_TILE_MAP_VORONOI, 8, 1, 8, 0, 8}, /* one cell filling the tile */
    };
    for (size_t i = 0; i < sizeof(cases) / sizeof(cases[0]); ++i)
        check_config(&cases[i]);
}

static void errors_have_codes(void)
{
    meso_error err = {0};
    meso_tile_map map;
    meso_split_cells sc;
    make_cells((meso_tile_map_params){MESO_TILE_MAP_VORONOI, 8, 4, 0, 1}, &map, &sc);
    meso_mesh m = load("sphere.obj");
    meso_voxel_grid g;
    assert(meso_voxel_grid_fit(&m, 4, 16, 1.0, &g, &err) == MESO_OK); /* R = 16, map 8 */
    meso_membership mb;
    assert(meso_membership_compute(&m, &g, &sc, MESO_VOXELIZE_AUTO, 1, &mb, &err) == MESO_ERR_INVALID_ARG &&
           err.code == MESO_MEMB_ISSUE_MISMATCH);
    fprintf(stderr, "    %s\n", err.message);
    assert(mb.classes == NULL);
    assert(meso_membership_compute(&m, &g, NULL, MESO_VOXELIZE_AUTO, 1, &mb, &err) == MESO_ERR_INVALID_ARG);
    meso_mesh_free(&m);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&map);
}

/* The encoding by hand: the record of each MIXED tile is found from the
 * class words and ranks as membership.h says, and holds the tags. */
static void encoding_is_as_documented(void)
{
    meso_error err = {0};
    meso_tile_map map;
    meso_split_cells sc;
    make_cells((meso_tile_map_params){MESO_TILE_MAP_VORONOI, 8, 40, 0, 9}, &map, &sc);
    assert(sc.split_count > 16); /* records of more than one word */
    meso_mesh m = load("torus.obj");
    meso_voxel_grid g;
    assert(meso_voxel_grid_fit(&m, 10, 8, 1.0, &g, &err) == MESO_OK);
    meso_membership mb;
    assert(meso_membership_compute(&m, &g, &sc, MESO_VOXELIZE_AUTO, 0, &mb, &err) == MESO_OK);
    assert(mb.words_per_tile == (2 * sc.split_count + 31) / 32);
    uint64_t seen = 0;
    for (uint64_t t = 0; t < mb.tile_count; ++t) {
        const uint32_t c = (mb.classes[t / 16] >> (2 * (t % 16))) & 3u;
        assert(c != 3);
        if (t % 16 == 0)
            assert(mb.rank[t / 16] == seen);
        if (c != MESO_TILE_MIXED)
            continue;
        const uint32_t* rec = mb.records + seen * mb.words_per_tile;
        const uint32_t tx = (uint32_t)(t % 10), ty = (uint32_t)(t / 10 % 10), tz = (uint32_t)(t / 100);
        int all_in = 1, all_out = 1;
        for (uint32_t s = 1; s <= sc.split_count; ++s) {
            const uint32_t tag = (rec[(s - 1) / 16] >> (2 * ((s - 1) % 16))) & 3u;
            assert(tag == (uint32_t)meso_membership_get(&mb, tx, ty, tz, s) && tag != MESO_MEMB_UNSET);
            all_in &= tag == MESO_MEMB_INSIDE;
            all_out &= tag == MESO_MEMB_OUTSIDE;
        }
        assert(!all_in && !all_out);
        ++seen;
    }
    assert(seen == mb.record_count && seen > 0);
    assert(mb.bytes == 4 * (2 * ((mb.tile_count + 15) / 16) + mb.record_count * mb.words_per_tile));
    fprintf(stderr, "    %llu tiles, %llu records of %u words: %llu bytes (thesis: %llu)\n",
            (unsigned long long)mb.tile_count, (unsigned long long)mb.record_count, mb.words_per_tile,
            (unsigned long long)mb.bytes, (unsigned long long)(16 * mb.tile_count));
    meso_membership_free(&mb);
    meso_mesh_free(&m);
    meso_split_cells_free(&sc);
    meso_tile_map_free(&map);
}

int main(void)
{
#if MESO_HAVE_CGAL
    TEST_RUN(errors_have_codes);
    TEST_RUN(encoding_is_as_documented);
    TEST_RUN(membership_matches_brute_force);
    fprintf(stderr, "membership: ok\n");
    return 0;
#else
    fprintf(stderr, "built without CGAL: skipped\n");
    return 77;
#endif
}
