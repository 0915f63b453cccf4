/* memory_budget.c — see memory_budget.h. */
#include "memory_budget.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include "bake_threads.h"

/* What a bake holds beside its own buffers: the program, its libraries
 * (OpenVDB, CGAL, TBB, OpenMesh are mapped and initialised), threads' stacks
 * and libc's arenas. Measured: 36 MiB peak RSS for the smallest bakes, and
 * peak RSS minus peak heap (heaptrack) 33..61 MiB on cells bakes. */
#define BASE_BYTES ((uint64_t)96 << 20)

uint64_t meso_memory_physical(void)
{
    const long pages = sysconf(_SC_PHYS_PAGES), page = sysconf(_SC_PAGE_SIZE);
    return pages > 0 && page > 0 ? meso_size_mul((uint64_t)pages, (uint64_t)page) : 0;
}

uint64_t meso_memory_default_budget(void)
{
    const uint64_t phys = meso_memory_physical();
    uint64_t b = phys ? phys / MESO_MEMORY_DEFAULT_DEN * MESO_MEMORY_DEFAULT_NUM : (uint64_t)8 << 30;
    struct rlimit rl;
    if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY && (uint64_t)rl.rlim_cur < b)
        b = (uint64_t)rl.rlim_cur;
    return b;
}

int meso_parse_size(const char* s, uint64_t* out)
{
    if (!s || !(*s >= '0' && *s <= '9'))
        return 0;
    /* The integer part exactly (plain byte counts up to 2^62), then an
     * optional fraction for suffixed values ("1.5G"). */
    uint64_t whole = 0;
    const char* p = s;
    for (; *p >= '0' && *p <= '9'; ++p) {
        if (whole > ((uint64_t)1 << 62) / 10)
            return 0;
        whole = whole * 10 + (uint64_t)(*p - '0');
    }
    double frac = 0, scale = 0.1;
    if (*p == '.') {
        ++p;
        if (!(*p >= '0' && *p <= '9'))
            return 0;
        for (; *p >= '0' && *p <= '9'; ++p, scale /= 10)
            frac += scale * (*p - '0');
    }
    unsigned shift = 0;
    switch (*p) {
    case 'k': case 'K': shift = 10; break;
    case 'm': case 'M': shift = 20; break;
    case 'g': case 'G': shift = 30; break;
    case 't': case 'T': shift = 40; break;
    case 0: break;
    default: return 0;
    }
    if (shift) {
        ++p;
        if (p[0] == 'i' && p[1] == 'B')
            p += 2;
        else if (p[0] == 'B')
            p += 1;
    } else if (frac > 0) {
        return 0; /* a fraction of a byte */
    }
    if (*p)
        return 0;
    if (!shift && (whole < 1 || whole > ((uint64_t)1 << 62)))
        return 0;
    const double v = ((double)whole + frac) * (double)((uint64_t)1 << shift);
    if (!(v >= 1) || v > (double)((uint64_t)1 << 62))
        return 0;
    *out = shift ? (uint64_t)v : whole;
    return 1;
}

const char* meso_format_size(uint64_t bytes, char* buf, size_t size)
{
    static const char* const unit[] = {"KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    if (bytes < 1024) {
        snprintf(buf, size, "%llu bytes", (unsigned long long)bytes);
        return buf;
    }
    double v = (double)bytes / 1024;
    int u = 0;
    while (v >= 1024 && u < 5) {
        v /= 1024;
        ++u;
    }
    snprintf(buf, size, v < 10 ? "%.1f %s" : "%.0f %s", v, unit[u]);
    return buf;
}

uint64_t meso_size_mul(uint64_t a, uint64_t b)
{
    return a && b > UINT64_MAX / a ? UINT64_MAX : a * b;
}

uint64_t meso_size_add(uint64_t a, uint64_t b)
{
    return a > UINT64_MAX - b ? UINT64_MAX : a + b;
}

meso_result meso_budget_check(uint64_t need, uint64_t budget, uint32_t code, meso_error* err, const char* what, ...)
{
    if (need <= budget)
        return MESO_OK;
    char w[256], n[32], b[32];
    va_list ap;
    va_start(ap, what);
    vsnprintf(w, sizeof w, what, ap);
    va_end(ap);
    return meso_bake_fail(err, code == MESO_LIMIT_ISSUE_REQUEST ? MESO_ERR_INVALID_ARG : MESO_ERR_CORRUPT, code,
                          "%s needs about %s, more than the memory budget %s; raise it with --max-memory SIZE "
                          "(default: half of physical memory)",
                          w, need == UINT64_MAX ? "more than any machine has" : meso_format_size(need, n, sizeof n),
                          meso_format_size(budget, b, sizeof b));
}

int meso_regular_file_size(FILE* fp, uint64_t* size)
{
    struct stat st;
    if (fstat(fileno(fp), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size < 0)
        return 0;
    *size = (uint64_t)st.st_size;
    return 1;
}

/* >>estimates -------------------------------------------------------------- */

/* Tiles near the surface, summed over triangles and capped at the tile
 * count. grow 0: the tiles each triangle meets (the voxelizer's own
 * triangle-box test, boxes grown a little more than it grows them), counted
 * per z-layer of tiles into layer[] (T2 entries) when not NULL; a triangle
 * whose bounding box spans more than 4096 tiles, or once 2^22 tests are
 * spent, counts its whole box. grow 1: every tile within one tile of a
 * triangle's bounding box. */
static uint64_t near_surface(const meso_mesh* m, const meso_voxel_grid* g, int grow, uint64_t* layer)
{
    const uint64_t T = meso_size_mul(meso_size_mul(g->tiles[0], g->tiles[1]), g->tiles[2]);
    const double edge = g->voxel_size * g->tile_res;
    const double half[3] = {edge * (0.5 + 1e-5), edge * (0.5 + 1e-5), edge * (0.5 + 1e-5)};
    uint64_t sum = 0, tests = 0;
    for (uint32_t t = 0; t < m->triangle_count; ++t) {
        double tv[9], a[3], b[3];
        for (int c = 0; c < 3; ++c)
            for (int k = 0; k < 3; ++k)
                tv[3 * c + k] = m->positions[3 * (size_t)m->indices[3 * (size_t)t + (size_t)c] + (size_t)k];
        for (int k = 0; k < 3; ++k) {
            const double lo = fmin(tv[k], fmin(tv[3 + k], tv[6 + k])), hi = fmax(tv[k], fmax(tv[3 + k], tv[6 + k]));
            a[k] = fmax(floor((lo - g->origin[k]) / edge - 1e-4) - grow, 0);
            b[k] = fmin(floor((hi - g->origin[k]) / edge + 1e-4) + grow, (double)g->tiles[k] - 1);
        }
        if (!(b[0] >= a[0] && b[1] >= a[1] && b[2] >= a[2]))
            continue;
        const uint64_t nx = (uint64_t)(b[0] - a[0] + 1), ny = (uint64_t)(b[1] - a[1] + 1);
        const uint64_t nz = (uint64_t)(b[2] - a[2] + 1), box = meso_size_mul(meso_size_mul(nx, ny), nz);
        const int exact = !grow && box <= 4096 && tests < ((uint64_t)1 << 22);
        tests += exact ? box : 0;
        for (uint64_t z = (uint64_t)a[2]; z <= (uint64_t)b[2]; ++z) {
            uint64_t n = nx * ny;
            if (exact) {
                n = 0;
                for (uint64_t y = (uint64_t)a[1]; y <= (uint64_t)b[1]; ++y)
                    for (uint64_t x = (uint64_t)a[0]; x <= (uint64_t)b[0]; ++x) {
                        const double c[3] = {g->origin[0] + (x + 0.5) * edge, g->origin[1] + (y + 0.5) * edge,
                                             g->origin[2] + (z + 0.5) * edge};
                        n += (uint64_t)meso_triangle_box_overlap(c, half, tv);
                    }
            }
            sum = meso_size_add(sum, n);
            if (layer)
                layer[z] = meso_size_add(layer[z], n);
            if (!exact && !layer) { /* the whole box at once */
                sum = meso_size_add(sum - n, box);
                break;
            }
        }
    }
    return sum < T ? sum : T;
}

uint64_t meso_cells_estimate(const meso_mesh* m, const meso_voxel_grid* g, uint64_t splits, int threads,
                             uint64_t* near)
{
    const uint64_t R = g->tile_res, V = R * R * R, T0 = g->tiles[0], T1 = g->tiles[1], T2 = g->tiles[2];
    const uint64_t T = meso_size_mul(meso_size_mul(T0, T1), T2), S = splits ? splits : 1;
    uint64_t* layer = calloc(T2 ? T2 : 1, sizeof(uint64_t));
    /* M0: tiles a triangle meets, a bound of the voxelizer's MIXED
     * tiles; M: one tile more each side, a bound of the tiles the merge may
     * change (they border MIXED ones) and of the MIXED tiles after it. */
    const uint64_t M0 = near_surface(m, g, 0, layer), M = near_surface(m, g, 1, NULL);
    if (near)
        *near = M;
    const uint64_t nt = (uint64_t)meso_bake_thread_count(threads);
    const uint64_t rec = 4 * ((2 * S + 31) / 32);                        /* one MEMB record */
    const uint64_t memb = meso_size_add(T / 2 + 8, meso_size_mul(rec, M)); /* classes + rank + records */
    /* Stage 1, voxelization and membership: tile map, labels, word masks;
     * the voxelizer's batch of MIXED bits (bake/voxelize.c: as many rows of
     * tiles as 64 MiB of bits at 4 MIXED tiles a row, at least 4 a thread;
     * a batch spans at most rows / T1 + 2 z-layers, so it holds no more
     * MIXED tiles than those layers have near the surface); per tile the
     * class, the merge flag and the index; per MIXED tile the growing ids
     * and tags, the merge's copy, the record. */
    const uint64_t words = (V + 63) / 64;
    uint64_t rows = ((uint64_t)64 << 20) / (4 * words * 8);
    if (rows < 4 * nt)
        rows = 4 * nt;
    uint64_t batch = meso_size_mul(rows, T0);
    if (batch > M0)
        batch = M0;
    if (layer) {
        const uint64_t span = rows / (T1 ? T1 : 1) + 2;
        uint64_t best = 0, win = 0;
        for (uint64_t z = 0; z < T2; ++z) {
            win = meso_size_add(win, layer[z]) - (z >= span ? layer[z - span] : 0);
            best = win > best ? win : best;
        }
        batch = best < batch ? best : batch;
        free(layer);
    }
    uint64_t a = meso_size_mul(7, V);
    a = meso_size_add(a, meso_size_mul(batch, words * 8));
    a = meso_size_add(a, meso_size_mul(2, T));
    a = meso_size_add(a, memb);
    a = meso_size_add(a, meso_size_mul(M0, 2 * (8 + S)));
    a = meso_size_add(a, meso_size_mul(M, 8 + S));
    a = meso_size_add(a, meso_size_mul(nt, 4 * R * R + 21 * T0));
    a = meso_size_add(a, meso_size_mul(m->triangle_count, 160));
    /* Stage 2, chunks and the write: tile map, labels, TILE (2 B a voxel,
     * 4 B past 65535 split cells), NRMM, COLR and the writer's copies; the
     * membership map, its MEMB chunk and the writer's copy. */
    const uint64_t tile_bytes = S > 65535 ? 4 : 2;
    uint64_t b = meso_size_mul(6 + 2 * (tile_bytes + 8), V);
    b = meso_size_add(b, meso_size_mul(3, memb));
    b = meso_size_add(b, meso_size_mul(m->triangle_count, 96));
    return meso_size_add(BASE_BYTES, a > b ? a : b);
}

uint64_t meso_texture_estimate(uint64_t texels)
{
    return meso_size_add(BASE_BYTES, meso_size_mul(texels, 11));
}

uint64_t meso_distmap_estimate(uint64_t cells)
{
    return meso_size_mul(cells, 4 + 2 + 8 + 4 + 4 + 4);
}

uint64_t meso_skeleton_estimate(uint64_t bytes, uint64_t lines)
{
    return meso_size_add(BASE_BYTES, meso_size_add(bytes, meso_size_mul(lines, 1024)));
}

meso_result meso_count_lines(const char* path, uint64_t* bytes, uint64_t* lines, meso_error* err)
{
    *bytes = *lines = 0;
    FILE* fp = fopen(path, "rb");
    if (!fp)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: cannot open: %s", path, strerror(errno));
    char buf[1 << 16];
    size_t got;
    int last = '\n';
    while ((got = fread(buf, 1, sizeof buf, fp)) > 0) {
        *bytes += got;
        for (const char* p = buf; (p = memchr(p, '\n', got - (size_t)(p - buf))) != NULL; ++p)
            ++*lines;
        last = buf[got - 1];
    }
    const int failed = ferror(fp);
    fclose(fp);
    if (failed)
        return meso_bake_fail(err, MESO_ERR_IO, 5001, "%s: read error", path);
    *lines += last != '\n';
    return MESO_OK;
}
