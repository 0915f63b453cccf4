/* Tile maps (bake/tile_map.c) against an independent brute force:
 *  - every voxel of Voronoi and sphere maps equals the nearest seed found by
 *    plain loops over all seeds and all 27 periodic images of each (integer
 *    arithmetic on the same lattice, so ties compare exactly);
 *  - the maps tile: the brute force evaluated one voxel beyond each of the six
 *    faces (x = R, x = -1, ...) equals the map on the opposite face;
 *  - the same map for 1 and 2 threads, and a golden checksum (the PRNG and
 *    the construction are specified, so the bytes must never change);
 *  - splitmix64's published first output;
 *  - parameter errors, raw bytes and raw files (sizes, codes, messages). */
#include "test_util.h"

#include <string.h>
#include <unistd.h>

#include "tile_map.h"

/* Brute force: nearest seed of lattice point p over 27 images, ties to the
 * lower index; 0 for spheres when none is within the radius. */
static uint16_t brute_index(const meso_tile_map* m, int64_t x, int64_t y, int64_t z)
{
    const int64_t S = MESO_TILE_MAP_SUBSTEPS, M = 2 * (int64_t)m->res * S;
    const int64_t p[3] = {(2 * x + 1) * S, (2 * y + 1) * S, (2 * z + 1) * S};
    uint64_t best = UINT64_MAX;
    uint16_t idx = 0;
    for (uint32_t k = 0; k < m->cell_count; ++k)
        for (int i = -1; i <= 1; ++i)
            for (int j = -1; j <= 1; ++j)
                for (int l = -1; l <= 1; ++l) {
                    const int64_t d0 = p[0] - ((int64_t)m->seeds[3 * k] + i * M);
                    const int64_t d1 = p[1] - ((int64_t)m->seeds[3 * k + 1] + j * M);
                    const int64_t d2 = p[2] - ((int64_t)m->seeds[3 * k + 2] + l * M);
                    const uint64_t d = (uint64_t)(d0 * d0) + (uint64_t)(d1 * d1) + (uint64_t)(d2 * d2);
                    if (d < best) {
                        best = d;
                        idx = (uint16_t)(k + 1);
                    }
                }
    if (m->kind == MESO_TILE_MAP_SPHERES && best > m->radius_sq)
        return 0;
    return idx;
}

static uint16_t at(const meso_tile_map* m, uint32_t x, uint32_t y, uint32_t z)
{
    return m->cells[x + m->res * (y + (size_t)m->res * z)];
}

static uint64_t fnv1a(const void* data, size_t n)
{
    const uint8_t* b = data;
    uint64_t h = 1469598103934665603ull;
    for (size_t i = 0; i < n; ++i)
        h = (h ^ b[i]) * 1099511628211ull;
    return h;
}

static void check_map(const meso_tile_map_params* p)
{
    meso_tile_map m;
    meso_error err;
    assert(meso_tile_map_generate(p, 1, &m, &err) == MESO_OK);
    const uint32_t R = m.res;
    size_t mismatches = 0, empty = 0;
    uint32_t used[65536 / 32] = {0};
    for (uint32_t z = 0; z < R; ++z)
        for (uint32_t y = 0; y < R; ++y)
            for (uint32_t x = 0; x < R; ++x) {
                const uint16_t c = at(&m, x, y, z);
                mismatches += c != brute_index(&m, x, y, z);
                mismatches += c != meso_tile_map_eval(&m, x, y, z);
                empty += c == 0;
                used[c / 32] |= 1u << (c % 32);
            }
    /* Seamless: one voxel beyond each face continues the opposite face. */
    size_t seams = 0;
    for (uint32_t a = 0; a < R; ++a)
        for (uint32_t b = 0; b < R; ++b) {
            seams += brute_index(&m, R, a, b) != at(&m, 0, a, b);
            seams += brute_index(&m, -1, a, b) != at(&m, R - 1, a, b);
            seams += brute_index(&m, a, R, b) != at(&m, a, 0, b);
            seams += brute_index(&m, a, -1, b) != at(&m, a, R - 1, b);
            seams += brute_index(&m, a, b, R) != at(&m, a, b, 0);
            seams += brute_index(&m, a, b, -1) != at(&m, a, b, R - 1);
            seams += meso_tile_map_eval(&m, (int64_t)R + a, -1 - (int64_t)R, 3 * (int64_t)R + b) !=
                     at(&m, a, R - 1, b);
        }
    uint32_t distinct = 0;
    for (uint32_t c = 1; c <= m.cell_count; ++c)
        distinct += (used[c / 32] >> (c % 32)) & 1u;
    fprintf(stderr, "    %s R=%u K=%u r=%.2f: %zu mismatches, %zu seam mismatches, %u of %u indices used, %zu empty\n",
            p->kind == MESO_TILE_MAP_VORONOI ? "voronoi" : "spheres", R, p->count, p->radius, mismatches, seams,
            distinct, m.cell_count, empty);
    assert(mismatches == 0 && seams == 0);
    if (p->kind == MESO_TILE_MAP_VORONOI)
        assert(empty == 0);
    meso_tile_map_free(&m);
}

static void voronoi_and_spheres_match_brute_force(void)
{
    const uint32_t res[] = {8, 13, 24};
    const uint32_t counts[] = {1, 2, 5, 12};
    uint64_t seed = 7;
    for (size_t i = 0; i < 3; ++i)
        for (size_t j = 0; j < 4; ++j)
            check_map(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, res[i], counts[j], 0.0, seed++});
    const double radii[] = {0.12, 0.3, 0.6};
    for (size_t i = 0; i < 3; ++i)
        for (size_t j = 1; j < 4; ++j)
            check_map(&(meso_tile_map_params){MESO_TILE_MAP_SPHERES, res[i], counts[j], radii[(i + j) % 3], seed++});
    /* More seeds than voxels: some own none. */
    check_map(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, 4, 40, 0.0, 1});
}

static void same_for_any_thread_count(void)
{
    const meso_tile_map_params ps[] = {
        {MESO_TILE_MAP_VORONOI, 48, 20, 0.0, 12345},
        {MESO_TILE_MAP_SPHERES, 40, 9, 0.2, 99},
    };
    /* Golden: the construction is specified (tile_map.h), so these bytes
     * never change, on any platform; a change here changes every baked file. */
    const uint64_t golden[] = {0xbac0425c8b0376e0ull, 0xc9f6baee8c00091aull};
    for (size_t i = 0; i < 2; ++i) {
        meso_tile_map a, b, c;
        meso_error err;
        assert(meso_tile_map_generate(&ps[i], 1, &a, &err) == MESO_OK);
        assert(meso_tile_map_generate(&ps[i], 2, &b, &err) == MESO_OK);
        assert(meso_tile_map_generate(&ps[i], 0, &c, &err) == MESO_OK);
        const size_t n = (size_t)a.res * a.res * a.res * sizeof(uint16_t);
        assert(memcmp(a.cells, b.cells, n) == 0 && memcmp(a.cells, c.cells, n) == 0);
        assert(memcmp(a.seeds, b.seeds, 3 * sizeof(uint32_t) * a.cell_count) == 0);
        fprintf(stderr, "    params %zu: fnv1a %016llx\n", i, (unsigned long long)fnv1a(a.cells, n));
        assert(fnv1a(a.cells, n) == golden[i]);
        meso_tile_map_free(&a);
        meso_tile_map_free(&b);
        meso_tile_map_free(&c);
    }
}

/* Real ties (equal squared distances) go to the lower index: R = 4 has
 * M = 8 S lattice points per edge and voxel centres at S, 3S, 5S, 7S; seeds
 * at x = 0 and x = 2S (same y, z) are equally near voxels 0 and 2. */
static void ties_go_to_the_lower_index(void)
{
    const int64_t S = MESO_TILE_MAP_SUBSTEPS;
    uint32_t seeds[6] = {0, 0, 0, (uint32_t)(2 * S), 0, 0};
    meso_tile_map m = {.kind = MESO_TILE_MAP_VORONOI, .res = 4, .cell_count = 2, .seeds = seeds};
    const uint16_t want[4] = {1, 2, 1, 1};
    for (int x = 0; x < 4; ++x)
        assert(meso_tile_map_eval(&m, x, 0, 0) == want[x] && brute_index(&m, x, 0, 0) == want[x]);
    seeds[0] = (uint32_t)(2 * S); /* swapped: the lower index is now the seed at 2S */
    seeds[3] = 0;
    const uint16_t want2[4] = {1, 1, 1, 2};
    for (int x = 0; x < 4; ++x)
        assert(meso_tile_map_eval(&m, x, 0, 0) == want2[x] && brute_index(&m, x, 0, 0) == want2[x]);
}

static void splitmix64_known_answer(void)
{
    /* First outputs from state 0 (Vigna's reference splitmix64.c). */
    uint64_t s = 0;
    assert(meso_splitmix64(&s) == 0xE220A8397B1DCDAFull);
    assert(meso_splitmix64(&s) == 0x6E789E6AA1B965F4ull);
}

static void bad_parameters_are_refused(void)
{
    const meso_tile_map_params bad[] = {
        {MESO_TILE_MAP_VORONOI, 0, 8, 0.0, 1},
        {MESO_TILE_MAP_VORONOI, MESO_TILE_MAP_MAX_RES + 1, 8, 0.0, 1},
        {MESO_TILE_MAP_VORONOI, 16, 0, 0.0, 1},
        {MESO_TILE_MAP_VORONOI, 16, MESO_TILE_MAP_MAX_CELLS + 1, 0.0, 1},
        {MESO_TILE_MAP_SPHERES, 16, 8, 0.0, 1},
        {MESO_TILE_MAP_SPHERES, 16, 8, 1.5, 1},
        {MESO_TILE_MAP_SPHERES, 16, 8, NAN, 1},
        {MESO_TILE_MAP_RAW, 16, 8, 0.0, 1},
    };
    for (size_t i = 0; i < sizeof(bad) / sizeof(bad[0]); ++i) {
        meso_tile_map m;
        meso_error err;
        memset(&m, 0xAB, sizeof(m));
        assert(meso_tile_map_generate(&bad[i], 1, &m, &err) == MESO_ERR_INVALID_ARG);
        assert(err.code == MESO_TILEMAP_ISSUE_PARAMS);
        assert(m.cells == NULL && m.seeds == NULL);
        fprintf(stderr, "    E%u %s\n", err.code, err.message);
    }
}

static char tmpdir[256];

static void raw_bytes_and_files(void)
{
    /* Little-endian uint16, x fastest. */
    const uint32_t R = 3;
    uint8_t bytes[2 * 27];
    for (uint32_t i = 0; i < 27; ++i) {
        const uint16_t v = (uint16_t)(i * 517u);
        bytes[2 * i] = (uint8_t)(v & 0xFF);
        bytes[2 * i + 1] = (uint8_t)(v >> 8);
    }
    meso_tile_map m;
    meso_error err;
    assert(meso_tile_map_from_raw(bytes, sizeof(bytes), R, &m, &err) == MESO_OK);
    assert(m.kind == MESO_TILE_MAP_RAW && m.res == 3 && m.cell_count == 26u * 517u && m.seeds == NULL);
    for (uint32_t i = 0; i < 27; ++i)
        assert(m.cells[i] == (uint16_t)(i * 517u));
    assert(meso_tile_map_eval(&m, -1, 4, 2) == at(&m, 2, 1, 2));
    meso_tile_map_free(&m);

    /* Wrong sizes: coded, and the message says what would fit. */
    assert(meso_tile_map_from_raw(bytes, sizeof(bytes) - 1, R, &m, &err) == MESO_ERR_CORRUPT);
    assert(err.code == MESO_TILEMAP_ISSUE_CONTENT && m.cells == NULL);
    fprintf(stderr, "    E%u %s\n", err.code, err.message);
    assert(meso_tile_map_from_raw(bytes, 16, R, &m, &err) == MESO_ERR_CORRUPT);
    assert(strstr(err.message, "that is R = 2"));
    fprintf(stderr, "    E%u %s\n", err.code, err.message);
    assert(meso_tile_map_from_raw(bytes, sizeof(bytes), 0, &m, &err) == MESO_ERR_INVALID_ARG);
    assert(err.code == MESO_TILEMAP_ISSUE_PARAMS);

    /* Files: exact, short, long, missing. */
    char path[512];
    snprintf(path, sizeof(path), "%s/map.raw", tmpdir);
    for (int variant = 0; variant < 3; ++variant) {
        FILE* fp = fopen(path, "wb");
        assert(fp);
        const size_t len = variant == 0 ? sizeof(bytes) : variant == 1 ? sizeof(bytes) - 2 : sizeof(bytes);
        assert(fwrite(bytes, 1, len, fp) == len);
        if (variant == 2)
            assert(fwrite(bytes, 1, 10, fp) == 10);
        assert(fclose(fp) == 0);
        const meso_result r = meso_tile_map_read_raw(path, R, &m, &err);
        if (variant == 0) {
            assert(r == MESO_OK && m.res == 3 && m.cells[26] == (uint16_t)(26u * 517u));
            meso_tile_map_free(&m);
        } else {
            assert(r == MESO_ERR_CORRUPT && err.code == MESO_TILEMAP_ISSUE_CONTENT && m.cells == NULL);
            assert(strstr(err.message, variant == 1 ? "52 bytes" : "64 bytes"));
            fprintf(stderr, "    E%u %s\n", err.code, err.message);
        }
    }
    snprintf(path, sizeof(path), "%s/missing.raw", tmpdir);
    assert(meso_tile_map_read_raw(path, R, &m, &err) == MESO_ERR_IO);
    assert(err.code == MESO_TILEMAP_ISSUE_FILE && strstr(err.message, "missing.raw"));
    fprintf(stderr, "    E%u %s\n", err.code, err.message);
}

int main(void)
{
    snprintf(tmpdir, sizeof(tmpdir), "/tmp/meso_cells_XXXXXX");
    assert(mkdtemp(tmpdir));
    TEST_RUN(splitmix64_known_answer);
    TEST_RUN(ties_go_to_the_lower_index);
    TEST_RUN(voronoi_and_spheres_match_brute_force);
    TEST_RUN(same_for_any_thread_count);
    TEST_RUN(bad_parameters_are_refused);
    TEST_RUN(raw_bytes_and_files);
    char cmd[300];
    snprintf(cmd, sizeof(cmd), "rm -rf '%s'", tmpdir);
    if (system(cmd) != 0)
        fprintf(stderr, "could not remove %s\n", tmpdir);
    fprintf(stderr, "test_tile_map: all passed\n");
    return 0;
}
