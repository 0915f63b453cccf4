/*
 * bench_mesh_read.c — read throughput of mesh files, per format: the mesh
 * guard alone (bake/mesh_guard.c) and the whole load (guard + the OpenMesh
 * adapter, what meso_bake_load_mesh does).
 *
 *   bench_mesh_read DIR [CSV [MB [RUNS]]]
 *
 * Writes into DIR a torus (a closed, honest mesh: a grid of quads split into
 * two triangles, shared vertices) of about MB megabytes (default 50) in each
 * format — OBJ, OFF, PLY ascii, PLY binary little-endian, STL binary, STL
 * ascii — then times RUNS (default 5, at least 5) reads of each and reports
 * the MEDIAN wall time and the median CPU time of the process (the machine
 * may be shared; CPU time is what the reader costs), as MB/s of file
 * (MB = 1e6 bytes). The table goes to stdout and to CSV when given. The
 * files are deleted at the end.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include <math.h>

#include "adapters.h"
#include "mesh_guard.h"

static double clock_s(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int cmp_d(const void* a, const void* b)
{
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static double median(double* v, int n)
{
    qsort(v, (size_t)n, sizeof(double), cmp_d);
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

typedef enum { F_OBJ, F_OFF, F_PLY_A, F_PLY_B, F_STL_B, F_STL_A, F_COUNT } kind;
static const char* const kind_name[F_COUNT] = {"OBJ", "OFF", "PLY ascii", "PLY binary", "STL binary", "STL ascii"};
static const char* const kind_file[F_COUNT] = {"t.obj", "t.off", "ta.ply", "tb.ply", "tb.stl", "ta.stl"};
/* approximate bytes per grid cell (one vertex, two triangles) */
static const double kind_cell[F_COUNT] = {75, 70, 70, 38, 100, 520};

static void vertex(uint32_t n, uint32_t m, uint32_t i, uint32_t j, float p[3])
{
    const double R = 1.0, r = 0.35, u = 2 * M_PI * (i % n) / n, v = 2 * M_PI * (j % m) / m;
    p[0] = (float)((R + r * cos(v)) * cos(u));
    p[1] = (float)((R + r * cos(v)) * sin(u));
    p[2] = (float)(r * sin(v));
}

/* Triangle t (of 2 n m) as vertex indices. */
static void triangle(uint32_t n, uint32_t m, uint64_t t, uint32_t c[3])
{
    uint32_t i = (uint32_t)(t / 2 / m), j = (uint32_t)(t / 2 % m);
    uint32_t a = i * m + j, b = ((i + 1) % n) * m + j, d = ((i + 1) % n) * m + (j + 1) % m, e = i * m + (j + 1) % m;
    if (t % 2 == 0)
        c[0] = a, c[1] = b, c[2] = d;
    else
        c[0] = a, c[1] = d, c[2] = e;
}

static void write_file(const char* path, kind k, uint32_t n, uint32_t m)
{
    FILE* f = fopen(path, "wb");
    if (!f) {
        perror(path);
        exit(1);
    }
    const uint64_t nv = (uint64_t)n * m, nt = 2 * nv;
    float p[3];
    uint32_t c[3];
    if (k == F_OFF)
        fprintf(f, "OFF\n%llu %llu 0\n", (unsigned long long)nv, (unsigned long long)nt);
    if (k == F_PLY_A || k == F_PLY_B)
        fprintf(f,
                "ply\nformat %s 1.0\nelement vertex %llu\nproperty float x\nproperty float y\nproperty float z\n"
                "element face %llu\nproperty list uchar int vertex_indices\nend_header\n",
                k == F_PLY_A ? "ascii" : "binary_little_endian", (unsigned long long)nv, (unsigned long long)nt);
    if (k == F_STL_B || k == F_STL_A) {
        if (k == F_STL_B) {
            char head[80] = "bench_mesh_read torus";
            uint32_t count = (uint32_t)nt;
            fwrite(head, 1, 80, f);
            fwrite(&count, 4, 1, f); /* little-endian host (x86-64, arm64) */
        } else {
            fputs("solid torus\n", f);
        }
        for (uint64_t t = 0; t < nt; ++t) {
            triangle(n, m, t, c);
            if (k == F_STL_B) {
                float rec[12] = {0};
                for (int q = 0; q < 3; ++q)
                    vertex(n, m, c[q] / m, c[q] % m, rec + 3 + 3 * q);
                fwrite(rec, 4, 12, f);
                fwrite("\0", 1, 2, f);
            } else {
                fputs(" facet normal 0 0 0\n  outer loop\n", f);
                for (int q = 0; q < 3; ++q) {
                    vertex(n, m, c[q] / m, c[q] % m, p);
                    fprintf(f, "   vertex %.6f %.6f %.6f\n", p[0], p[1], p[2]);
                }
                fputs("  endloop\n endfacet\n", f);
            }
        }
        if (k == F_STL_A)
            fputs("endsolid torus\n", f);
        fclose(f);
        return;
    }
    for (uint32_t i = 0; i < n; ++i)
        for (uint32_t j = 0; j < m; ++j) {
            vertex(n, m, i, j, p);
            if (k == F_PLY_B)
                fwrite(p, 4, 3, f);
            else
                fprintf(f, "%s%.6f %.6f %.6f\n", k == F_OBJ ? "v " : "", p[0], p[1], p[2]);
        }
    for (uint64_t t = 0; t < nt; ++t) {
        triangle(n, m, t, c);
        if (k == F_OBJ) {
            fprintf(f, "f %u %u %u\n", c[0] + 1, c[1] + 1, c[2] + 1);
        } else if (k == F_PLY_B) {
            uint8_t three = 3;
            int32_t ic[3] = {(int32_t)c[0], (int32_t)c[1], (int32_t)c[2]};
            fwrite(&three, 1, 1, f);
            fwrite(ic, 4, 3, f);
        } else {
            fprintf(f, "3 %u %u %u\n", c[0], c[1], c[2]);
        }
    }
    fclose(f);
}

int main(int argc, char** argv)
{
    if (argc < 2) {
        fprintf(stderr, "usage: bench_mesh_read DIR [CSV [MB [RUNS]]]\n");
        return 1;
    }
    const char* dir = argv[1];
    FILE* csv = argc > 2 ? fopen(argv[2], "w") : NULL;
    double mb = argc > 3 ? atof(argv[3]) : 50.0;
    int runs = argc > 4 ? atoi(argv[4]) : 5;
    if (runs < 5)
        runs = 5;
    if (csv)
        fprintf(csv, "format,file_mb,vertices,triangles,runs,guard_wall_mbs,guard_cpu_mbs,load_wall_mbs,load_cpu_mbs,"
                     "load_median_wall_s\n");
    printf("%-11s %8s %9s %9s | %12s %12s | %12s %12s %9s\n", "format", "MB", "vertices", "triangles",
           "guard MB/s", "(cpu)", "load MB/s", "(cpu)", "load s");
    for (int k = 0; k < F_COUNT; ++k) {
        uint32_t side = (uint32_t)sqrt(mb * 1e6 / kind_cell[k]);
        if (side < 8)
            side = 8;
        char path[4096];
        snprintf(path, sizeof(path), "%s/%s", dir, kind_file[k]);
        write_file(path, (kind)k, side, side);
        struct stat sb;
        if (stat(path, &sb) != 0) {
            perror(path);
            return 1;
        }
        const double file_mb = (double)sb.st_size / 1e6;
        double gw[64], gc[64], lw[64], lc[64];
        if (runs > 64)
            runs = 64;
        meso_mesh_guard_stats st = {0, 0, 0};
        for (int r = 0; r < runs; ++r) {
            meso_error err = {0};
            double w0 = clock_s(CLOCK_MONOTONIC), c0 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            if (meso_mesh_guard_check_file(path, 0, &st, &err) != MESO_OK) {
                fprintf(stderr, "bench_mesh_read: guard refused %s: %s\n", path, err.message);
                return 1;
            }
            double w1 = clock_s(CLOCK_MONOTONIC), c1 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            meso_mesh m;
            if (meso_openmesh_read(path, &m, NULL, &err) != MESO_OK) {
                fprintf(stderr, "bench_mesh_read: OpenMesh refused %s: %s\n", path, err.message);
                return 1;
            }
            double w2 = clock_s(CLOCK_MONOTONIC), c2 = clock_s(CLOCK_PROCESS_CPUTIME_ID);
            if (m.vertex_count != side * side || m.triangle_count != 2 * side * side) {
                fprintf(stderr, "bench_mesh_read: %s read as %u vertices, %u triangles\n", path, m.vertex_count,
                        m.triangle_count);
                return 1;
            }
            meso_mesh_free(&m);
            gw[r] = w1 - w0;
            gc[r] = c1 - c0;
            lw[r] = w2 - w0;
            lc[r] = c2 - c0;
        }
        double mgw = median(gw, runs), mgc = median(gc, runs), mlw = median(lw, runs), mlc = median(lc, runs);
        printf("%-11s %8.1f %9llu %9llu | %12.1f %12.1f | %12.2f %12.2f %9.2f\n", kind_name[k], file_mb,
               (unsigned long long)side * side, (unsigned long long)st.triangles, file_mb / mgw, file_mb / mgc,
               file_mb / mlw, file_mb / mlc, mlw);
        fflush(stdout);
        if (csv)
            fprintf(csv, "%s,%.2f,%llu,%llu,%d,%.2f,%.2f,%.3f,%.3f,%.3f\n", kind_name[k], file_mb,
                    (unsigned long long)side * side, (unsigned long long)st.triangles, runs, file_mb / mgw,
                    file_mb / mgc, file_mb / mlw, file_mb / mlc, mlw);
        remove(path);
    }
    if (csv)
        fclose(csv);
    return 0;
}
