/*
 * bench_voxelize.c — sparse inside/outside voxelization (bake/voxelize.c)
 * on a closed mesh, against OpenVDB's narrow-band level set (the issue #6
 * baseline: OpenVDB's filled SDF of the bunny Loop-subdivided to 1.69 M
 * triangles took 34 s at 512 voxels across, its narrow band 8.1 s).
 *
 *   bench_voxelize [CSV] [goal] [MESH]
 *
 * Meshes: MESH (default: the bundled tests/data/spot_low_resolution.obj,
 * 1654 triangles) and the same split 1 -> 4 at edge midpoints until it has
 * at least 1.6 M triangles (spot: 5 times, 1.69 M, the count;
 * midpoints, not Loop's smoothing, so the shape is the same and only the
 * triangle count changes). The checked-in voxelize.csv was measured on the
 * Stanford bunny (6598 triangles, split 4 times), which cannot be bundled
 * (its terms forbid commercial use): pass a copy of it as MESH to repeat
 * those rows. Rows: meso (AUTO: parity on a closed mesh)
 * at 512 and 1024 voxels across, tiles of 8^3 and 32^3, 2 threads; OpenVDB
 * meshToLevelSet (half width 3 voxels) at the same voxel size. Every run is
 * in a child process, so its peak RSS (wait4) is its own. With `goal`, also
 * the goal setup: 64^3 tile map x 128^3 tiles (N = 8192), the
 * membership map included (Voronoi, 8 seeds), on the plain mesh, instead
 * of the rows above.
 */
#include "meso_clock.h"
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "adapters.h"
#include "membership.h"
#include "test_util.h"
#include "voxelize.h"


static int cmp_u64(const void* pa, const void* pb)
{
    const uint64_t a = *(const uint64_t*)pa, b = *(const uint64_t*)pb;
    return (a > b) - (a < b);
}

/* One level of 1 -> 4 midpoint subdivision. */
static void subdivide(meso_mesh* m)
{
    const size_t nf = m->triangle_count, nv = m->vertex_count;
    uint64_t* key = malloc(sizeof(uint64_t) * 3 * nf); /* min << 32 | max, sorted, unique */
    size_t ne = 0;
    for (size_t f = 0; f < nf; ++f)
        for (int c = 0; c < 3; ++c) {
            const uint64_t a = m->indices[3 * f + (size_t)c], b = m->indices[3 * f + (size_t)(c + 1) % 3];
            key[ne++] = a < b ? a << 32 | b : b << 32 | a;
        }
    qsort(key, ne, sizeof(uint64_t), cmp_u64);
    size_t u = 0;
    for (size_t i = 0; i < ne; ++i)
        if (!u || key[u - 1] != key[i])
            key[u++] = key[i];
    float* pos = malloc(sizeof(float) * 3 * (nv + u));
    uint32_t* idx = malloc(sizeof(uint32_t) * 12 * nf);
    memcpy(pos, m->positions, sizeof(float) * 3 * nv);
    for (size_t e = 0; e < u; ++e)
        for (int k = 0; k < 3; ++k)
            pos[3 * (nv + e) + (size_t)k] =
                0.5f * (m->positions[3 * (key[e] >> 32) + (size_t)k] + m->positions[3 * (key[e] & 0xFFFFFFFFu) + (size_t)k]);
    for (size_t f = 0; f < nf; ++f) {
        uint32_t v[3], mid[3];
        for (int c = 0; c < 3; ++c)
            v[c] = m->indices[3 * f + (size_t)c];
        for (int c = 0; c < 3; ++c) {
            const uint64_t a = v[c], b = v[(c + 1) % 3], k = a < b ? a << 32 | b : b << 32 | a;
            size_t lo = 0, hi = u;
            while (lo < hi) {
                const size_t md = (lo + hi) / 2;
                if (key[md] < k)
                    lo = md + 1;
                else
                    hi = md;
            }
            mid[c] = (uint32_t)(nv + lo);
        }
        const uint32_t t[4][3] = {{v[0], mid[0], mid[2]}, {mid[0], v[1], mid[1]}, {mid[2], mid[1], v[2]},
                                  {mid[0], mid[1], mid[2]}};
        memcpy(idx + 12 * f, t, sizeof(t));
    }
    free(key);
    free(m->positions);
    free(m->indices);
    free(m->normals);
    free(m->uvs);
    free(m->corner_uvs);
    m->normals = m->uvs = m->corner_uvs = NULL;
    m->positions = pos;
    m->indices = idx;
    m->vertex_count = (uint32_t)(nv + u);
    m->triangle_count = (uint32_t)(4 * nf);
}

typedef struct result {
    double seconds;
    uint64_t mixed, evaluated, rays, exact, cells_inside;
    int method;
    int ok;
} result;

/* Run `what` in a child; returns its result and peak RSS (MiB). */
static result run_child(int what, const meso_mesh* m, uint32_t tiles, uint32_t R, double* rss_mib)
{
    int fd[2];
    result res = {0};
    if (pipe(fd) != 0)
        return res;
    const pid_t pid = fork();
    if (pid == 0) {
        close(fd[0]);
        meso_error err = {0};
        meso_voxel_grid g;
        result r = {0};
        if (meso_voxel_grid_fit(m, tiles, R, 1.0, &g, &err) == MESO_OK) {
            if (what == 0) { /* meso: stream, count */
                meso_voxels v;
                if (meso_voxelize(m, &g, MESO_VOXELIZE_AUTO, 2, &v, &err) == MESO_OK) {
                    r = (result){v.stats.seconds, v.stats.tiles_mixed, v.stats.voxels_evaluated, v.stats.rows,
                                 v.stats.exact_predicates, 0, (int)v.stats.method, 1};
                    meso_voxels_free(&v);
                }
            } else if (what == 1) { /* OpenVDB narrow band at the same voxel size */
#if MESO_HAVE_OPENVDB
                meso_vdb_grid* vg = NULL;
                const double t0 = meso_seconds();
                if (meso_vdb_level_set(m, g.voxel_size, 3.0f, &vg, &err) == MESO_OK) {
                    r.seconds = meso_seconds() - t0;
                    r.evaluated = meso_vdb_active_voxels(vg);
                    r.ok = 1;
                    meso_vdb_destroy(vg);
                }
#endif
            } else { /* membership: Voronoi 8 seeds at R */
                meso_tile_map map;
                meso_split_cells sc;
                meso_membership mb;
                const double t0 = meso_seconds();
                if (meso_tile_map_generate(&(meso_tile_map_params){MESO_TILE_MAP_VORONOI, R, 8, 0, 1}, 2, &map, &err) ==
                        MESO_OK &&
                    meso_split_cells_compute(&map, 2, &sc, &err) == MESO_OK &&
                    meso_membership_compute(m, &g, &sc, MESO_VOXELIZE_AUTO, 2, &mb, &err) == MESO_OK) {
                    r = (result){meso_seconds() - t0, mb.voxelize.tiles_mixed, mb.voxelize.voxels_evaluated, mb.voxelize.rows,
                                 mb.bytes, mb.cells_inside, (int)mb.voxelize.method, 1};
                    fprintf(stderr, "  goal: voxelization %.1f s, membership total %.1f s, %llu bytes (thesis %llu)\n",
                            mb.voxelize.seconds, mb.seconds, (unsigned long long)mb.bytes,
                            (unsigned long long)(16 * mb.tile_count));
                }
            }
        }
        if (!r.ok)
            fprintf(stderr, "bench_voxelize: %s\n", err.message);
        if (write(fd[1], &r, sizeof(r)) != (ssize_t)sizeof(r))
            _exit(1);
        _exit(0);
    }
    close(fd[1]);
    if (read(fd[0], &res, sizeof(res)) != (ssize_t)sizeof(res))
        res.ok = 0;
    close(fd[0]);
    struct rusage u;
    int status = 0;
    wait4(pid, &status, 0, &u);
    *rss_mib = (double)u.ru_maxrss / 1024.0;
    return res;
}

int main(int argc, char** argv)
{
    const char* csv = argc > 1 ? argv[1] : NULL;
    int goal = 0;
    char mesh_path[4096];
    snprintf(mesh_path, sizeof(mesh_path), "%s", test_data("spot_low_resolution.obj"));
    for (int i = 2; i < argc; ++i) {
        if (strcmp(argv[i], "goal") == 0)
            goal = 1;
        else
            snprintf(mesh_path, sizeof(mesh_path), "%s", argv[i]);
    }
    /* the file's stem names the rows */
    char name[4096], name_fine[4200];
    const char* base = strrchr(mesh_path, '/');
    snprintf(name, sizeof(name), "%s", base ? base + 1 : mesh_path);
    char* dot = strrchr(name, '.');
    if (dot)
        *dot = 0;
    meso_mesh plain;
    meso_error err = {0};
    if (meso_openmesh_read(mesh_path, &plain, NULL, &err) != MESO_OK) {
        fprintf(stderr, "bench_voxelize: %s not readable (%s)\n", mesh_path, err.message);
        return 1;
    }
    FILE* out = csv ? fopen(csv, "w") : stdout;
    if (!out)
        return 1;
    fprintf(out, "mesh,triangles,tool,voxels_across,tile_res,seconds,peak_rss_mib,mixed_tiles,voxels_evaluated,"
                 "rays,exact_predicates\n");
    meso_mesh fine = {0};
    fine.vertex_count = plain.vertex_count;
    fine.triangle_count = plain.triangle_count;
    fine.positions = malloc(sizeof(float) * 3 * plain.vertex_count);
    fine.indices = malloc(sizeof(uint32_t) * 3 * plain.triangle_count);
    memcpy(fine.positions, plain.positions, sizeof(float) * 3 * plain.vertex_count);
    memcpy(fine.indices, plain.indices, sizeof(uint32_t) * 3 * plain.triangle_count);
    int levels = 0;
    for (; fine.triangle_count < 1600000u && !goal; ++levels)
        subdivide(&fine);
    snprintf(name_fine, sizeof(name_fine), "%s_x%u", name, 1u << (2 * levels));
    const meso_mesh* meshes[2] = {&plain, &fine};
    const char* names[2] = {name, name_fine};
    static const uint32_t across[2] = {512, 1024}, res[2] = {8, 32};
    for (int mi = 0; mi < 2 && !goal; ++mi)
        for (int a = 0; a < 2; ++a) {
            for (int r = 0; r < 2; ++r) {
                double rss;
                const result x = run_child(0, meshes[mi], across[a] / res[r], res[r], &rss);
                if (!x.ok)
                    continue;
                fprintf(out, "%s,%u,meso_%s,%u,%u,%.3f,%.1f,%llu,%llu,%llu,%llu\n", names[mi],
                        meshes[mi]->triangle_count, meso_voxelizer_name((meso_voxelizer)x.method), across[a], res[r],
                        x.seconds, rss, (unsigned long long)x.mixed, (unsigned long long)x.evaluated,
                        (unsigned long long)x.rays, (unsigned long long)x.exact);
                fflush(out);
            }
            double rss;
            const result v = run_child(1, meshes[mi], across[a] / 8, 8, &rss);
            if (v.ok) {
                fprintf(out, "%s,%u,openvdb_narrow_band,%u,,%.3f,%.1f,,%llu,,\n", names[mi], meshes[mi]->triangle_count,
                        across[a], v.seconds, rss, (unsigned long long)v.evaluated);
                fflush(out);
            }
        }
    if (goal) { /* 64^3 tile map x 128^3 tiles */
        double rss;
        const result x = run_child(2, &plain, 128, 64, &rss);
        if (x.ok)
            fprintf(out, "%s,%u,meso_membership_%s,8192,64,%.3f,%.1f,%llu,%llu,%llu,\n", name, plain.triangle_count,
                    meso_voxelizer_name((meso_voxelizer)x.method), x.seconds, rss, (unsigned long long)x.mixed,
                    (unsigned long long)x.evaluated, (unsigned long long)x.rays);
    }
    if (csv)
        fclose(out);
    meso_mesh_free(&plain);
    meso_mesh_free(&fine);
    return 0;
}
