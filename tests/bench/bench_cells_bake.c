/*
 * bench_cells_bake.c — the thesis's Table 5.1 (papers/cell-based-object-
 * representation.md §5.1) through `mesobake cells` on the bunny: four
 * setups of 8192 voxels along the longest axis, tile map (cell map)
 * resolution R^3 x T^3 tiles = 256^3 x 32^3, 128^3 x 64^3, 64^3 x 128^3 and
 * 32^3 x 256^3, Voronoi tile map with 8 seeds (as the thesis), 2 threads.
 *
 *   bench_cells_bake MESOBAKE BUNNY.obj OUT_DIR [quick]
 *
 * Every setup runs `MESOBAKE cells -i BUNNY.obj -o X.meso --tile-res R
 * --tiles T --tile-map voronoi:8 -j 2 --report X.json -v` as a child process
 * (fork + execv, like bench_voxelize.c's children): wall seconds by our
 * clock, peak RSS of that process by wait4 (ru_maxrss), seconds_total and
 * the counts from the report, the stage times from the -v lines, and the
 * bytes per chunk from the file's table of contents (meso_file_open_path,
 * stored_size per chunk type). The .meso files go to a scratch directory
 * under $TMPDIR (default /tmp) and are deleted after measuring.
 *
 * Writes OUT_DIR/cells_table51.csv (quick: OUT_DIR/cells_table51_quick.csv,
 * only the two small-memory setups 128^3 x 64^3 and 64^3 x 128^3), one row
 * per setup next to the thesis's numbers (its MB are MiB: 256^3 voxels at
 * one byte = 16 MB). A setup that fails or runs past the time limit
 * (MESO_BENCH_CELLS_TIMEOUT seconds, default 900) gets a row with status
 * failed / timeout and the last line mesobake printed on stderr; the exit
 * status is 1 when a setup failed (a timeout alone is a result: 0).
 *
 * Map bytes, ours against the thesis's:
 *   tile map   TILE (u16 per tile-map voxel) + SPLT (24 B per split cell);
 *              the thesis's cell map is 1 B per voxel.
 *   colour     COLR, RGBA8 at the tile-map resolution R^3; the thesis used a
 *              fixed 128^3 RGBA8 colour map (8 MiB in every row).
 *   normal     NRMM, 2 x u16 octahedral per voxel; the thesis 16 B per voxel.
 *   membership MEMB, sparse (2 bits per tile + a record per mixed tile,
 *              FORMAT.md §7.2 kind 3); the thesis 16 B per tile, dense.
 * Exit 1 when the mesh or mesobake is missing. The mesh is an argument:
 * meson's benchmark and run_benchmarks.sh pass the bundled
 * tests/data/spot_low_resolution.obj (run_benchmarks.sh: $MESO_BENCH_MESH
 * if set); the checked-in cells_table51.csv was measured on the thesis's
 * Stanford bunny, which cannot be bundled (its terms forbid commercial use).
 */
#include "meso_clock.h"
#include <errno.h>
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "meso_file.h"

#define MIB (1024.0 * 1024.0)

typedef struct setup {
    uint32_t tile_res, tiles;
    /* Table 5.1, bytes (the thesis's MB/KB are binary). */
    uint64_t thesis_cell, thesis_colour, thesis_normal, thesis_memb, thesis_total;
} setup;

static const setup setups[4] = {
    {256, 32, 16u << 20, 8u << 20, 256u << 20, 512u << 10, 280u << 20},
    {128, 64, 2u << 20, 8u << 20, 32u << 20, 4u << 20, 46u << 20},
    {64, 128, 256u << 10, 8u << 20, 4u << 20, 32u << 20, 44u << 20},
    {32, 256, 32u << 10, 8u << 20, 512u << 10, 256u << 20, 264u << 20},
};

typedef struct measured {
    const char* status; /* ok, failed, timeout */
    char error[512];
    double wall_s, rss_mib;
    /* report */
    double seconds_total, voxels_across, tiles, split_cells, cells_per_tile, tiles_mixed, cells_inside,
        cells_outside, cells_intersected;
    char voxelizer[32];
    /* -v stage times (seconds; < 0 when not found) */
    double tile_map_s, voxelize_s, maps_s;
    /* file */
    uint64_t file_bytes, mesh, cell, tile, splt, memb, nrmm, colr, other;
} measured;


static char* slurp(const char* path)
{
    FILE* f = fopen(path, "rb");
    if (!f)
        return NULL;
    size_t cap = 4096, n = 0;
    char* s = malloc(cap);
    for (size_t k; s && (k = fread(s + n, 1, cap - n - 1, f)) > 0;) {
        n += k;
        if (cap - n - 1 == 0) {
            char* t = realloc(s, 2 * cap);
            if (!t) {
                free(s);
                s = NULL;
                break;
            }
            s = t;
            cap *= 2;
        }
    }
    fclose(f);
    if (s)
        s[n] = 0;
    return s;
}

static double jnum(const cJSON* o, const char* key)
{
    const cJSON* v = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(v) ? v->valuedouble : -1.0;
}

/* Stage times from mesobake -v ("mesobake: ... (N ms)") and the last line
 * (the error message when the bake failed). */
static void parse_log(const char* log_path, measured* r)
{
    r->tile_map_s = r->voxelize_s = r->maps_s = -1.0;
    char* s = slurp(log_path);
    if (!s)
        return;
    char last[256] = "";
    for (char* line = strtok(s, "\n"); line; line = strtok(NULL, "\n")) {
        snprintf(last, sizeof(last), "%s", line);
        const char* p = strrchr(line, '(');
        double ms;
        if (!p || sscanf(p, "(%lf ms)", &ms) != 1)
            continue;
        if (strstr(line, "tile map"))
            r->tile_map_s = ms / 1000.0;
        else if (strstr(line, "voxels across"))
            r->voxelize_s = ms / 1000.0;
        else if (strstr(line, "normal and colour maps"))
            r->maps_s = ms / 1000.0;
    }
    if (strcmp(r->status, "ok") != 0 && !r->error[0])
        snprintf(r->error, sizeof(r->error), "%s", last);
    free(s);
}

static void read_report(const char* path, measured* r)
{
    char* s = slurp(path);
    cJSON* j = s ? cJSON_Parse(s) : NULL;
    free(s);
    if (!j) {
        r->status = "failed";
        snprintf(r->error, sizeof(r->error), "report missing or not JSON");
        return;
    }
    r->seconds_total = jnum(j, "seconds_total");
    r->voxels_across = jnum(j, "voxels_across");
    r->tiles = jnum(j, "tiles");
    r->split_cells = jnum(j, "split_cells");
    r->cells_per_tile = jnum(j, "cells_per_tile");
    r->tiles_mixed = jnum(j, "tiles_mixed");
    r->cells_inside = jnum(j, "cells_inside");
    r->cells_outside = jnum(j, "cells_outside");
    r->cells_intersected = jnum(j, "cells_intersected");
    const cJSON* v = cJSON_GetObjectItemCaseSensitive(j, "voxelizer");
    snprintf(r->voxelizer, sizeof(r->voxelizer), "%s", cJSON_IsString(v) ? v->valuestring : "");
    cJSON_Delete(j);
}

static void read_chunks(const char* path, measured* r)
{
    meso_file* f = NULL;
    meso_error err = {0};
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK) {
        r->status = "failed";
        snprintf(r->error, sizeof(r->error), "open: %s", err.message);
        return;
    }
    r->file_bytes = meso_file_size(f);
    const uint32_t n = meso_file_chunk_count(f);
    for (uint32_t i = 0; i < n; ++i) {
        const meso_chunk_info* c = meso_file_chunk(f, i);
        const uint64_t b = c->stored_size;
        switch (c->type) {
        case MESO_CHUNK_MESH: r->mesh += b; break;
        case MESO_CHUNK_CELL: r->cell += b; break;
        case MESO_CHUNK_TILE: r->tile += b; break;
        case MESO_CHUNK_SPLT: r->splt += b; break;
        case MESO_CHUNK_MEMB: r->memb += b; break;
        case MESO_CHUNK_NRMM: r->nrmm += b; break;
        case MESO_CHUNK_COLR: r->colr += b; break;
        default: r->other += b; break;
        }
    }
    meso_file_close(f);
}

/* One bake in a child process; wall clock and wait4's peak RSS are its own. */
static measured run_setup(const char* mesobake, const char* bunny, const char* work, const setup* s, double timeout)
{
    measured r = {.status = "ok"};
    char out[4160], rep[4160], log[4160], res[16], til[16];
    snprintf(out, sizeof(out), "%s/cells_%u_%u.meso", work, s->tile_res, s->tiles);
    snprintf(rep, sizeof(rep), "%s/cells_%u_%u.json", work, s->tile_res, s->tiles);
    snprintf(log, sizeof(log), "%s/cells_%u_%u.log", work, s->tile_res, s->tiles);
    snprintf(res, sizeof(res), "%u", s->tile_res);
    snprintf(til, sizeof(til), "%u", s->tiles);
    char* argv[] = {(char*)mesobake, "cells", "-i", (char*)bunny, "-o", out, "--tile-res", res, "--tiles", til,
                    "--tile-map", "voronoi:8", "-j", "2", "--report", rep, "-v", NULL};
    fprintf(stderr, "bench_cells_bake:");
    for (char** a = argv; *a; ++a)
        fprintf(stderr, " %s", *a);
    fprintf(stderr, "\n");
    fflush(NULL);
    const double t0 = meso_seconds();
    const pid_t pid = fork();
    if (pid < 0) {
        r.status = "failed";
        snprintf(r.error, sizeof(r.error), "fork: %s", strerror(errno));
        return r;
    }
    if (pid == 0) {
        const int fd = open(log, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd >= 0) {
            dup2(fd, STDERR_FILENO);
            dup2(fd, STDOUT_FILENO);
            close(fd);
        }
        execv(mesobake, argv);
        fprintf(stderr, "exec %s: %s\n", mesobake, strerror(errno));
        _exit(127);
    }
    struct rusage u = {0};
    int status = 0, killed = 0;
    for (;;) {
        const pid_t w = wait4(pid, &status, WNOHANG, &u);
        if (w == pid)
            break;
        if (w < 0 && errno != EINTR) {
            r.status = "failed";
            snprintf(r.error, sizeof(r.error), "wait4: %s", strerror(errno));
            return r;
        }
        if (!killed && meso_seconds() - t0 > timeout) {
            kill(pid, SIGKILL);
            killed = 1;
        }
        nanosleep(&(struct timespec){0, 5000000}, NULL);
    }
    r.wall_s = meso_seconds() - t0;
    r.rss_mib = (double)u.ru_maxrss / 1024.0;
    if (killed) {
        r.status = "timeout";
        snprintf(r.error, sizeof(r.error), "killed after %.0f s (MESO_BENCH_CELLS_TIMEOUT)", timeout);
    } else if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        r.status = "failed";
        if (WIFSIGNALED(status))
            snprintf(r.error, sizeof(r.error), "killed by signal %d", WTERMSIG(status));
    }
    if (strcmp(r.status, "ok") == 0) {
        read_report(rep, &r);
        if (strcmp(r.status, "ok") == 0)
            read_chunks(out, &r);
    }
    parse_log(log, &r);
    fprintf(stderr, "  %s: wall %.2f s (report %.2f s), peak RSS %.1f MiB, %llu bytes%s%s\n", r.status, r.wall_s,
            r.seconds_total, r.rss_mib, (unsigned long long)r.file_bytes, r.error[0] ? ": " : "", r.error);
    remove(out);
    remove(rep);
    remove(log);
    return r;
}

/* CSV-safe copy: no commas, quotes or newlines. */
static const char* csv_text(char* s)
{
    for (char* p = s; *p; ++p)
        if (*p == ',' || *p == '"' || *p == '\n' || *p == '\r')
            *p = ';';
    return s;
}

int main(int argc, char** argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: bench_cells_bake MESOBAKE MESH OUT_DIR [quick]\n");
        return 2;
    }
    const char *mesobake = argv[1], *bunny = argv[2], *dir = argv[3];
    const int quick = argc > 4 && strcmp(argv[4], "quick") == 0;
    if (access(bunny, R_OK) != 0 || access(mesobake, X_OK) != 0) {
        fprintf(stderr, "bench_cells_bake: %s or %s not there\n", bunny, mesobake);
        return 1;
    }
    const char* t = getenv("MESO_BENCH_CELLS_TIMEOUT");
    const double timeout = t && atof(t) > 0 ? atof(t) : 900.0;
    const char* tmp = getenv("TMPDIR");
    char work[4096];
    snprintf(work, sizeof(work), "%s/bench_cells_XXXXXX", tmp && *tmp ? tmp : "/tmp");
    if (!mkdtemp(work)) {
        fprintf(stderr, "bench_cells_bake: mkdtemp %s: %s\n", work, strerror(errno));
        return 1;
    }
    char csv[4096];
    snprintf(csv, sizeof(csv), "%s/cells_table51%s.csv", dir, quick ? "_quick" : "");
    FILE* out = fopen(csv, "w");
    if (!out) {
        fprintf(stderr, "bench_cells_bake: cannot write %s\n", csv);
        rmdir(work);
        return 1;
    }
    fprintf(out, "setup,tile_res,tiles,status,seconds_report,seconds_wall,peak_rss_mib,file_bytes,"
                 "tile_map_bytes,colour_bytes_ours_R3_rgba8,normal_bytes,membership_bytes,mesh_bytes,other_bytes,"
                 "thesis_cell_map_bytes,thesis_colour_bytes_fixed_128c_rgba8,thesis_normal_bytes,"
                 "thesis_membership_bytes,thesis_total_bytes,voxels_across,effective_voxels,tiles_total,"
                 "split_cells,cells_per_tile,tiles_mixed,cells_inside,cells_outside,cells_intersected,voxelizer,"
                 "tile_map_s,voxelize_membership_s,normal_colour_s,error\n");
    int failures = 0, errors = 0;
    for (int i = 0; i < 4; ++i) {
        const setup* s = &setups[i];
        if (quick && (i == 0 || i == 3))
            continue;
        measured r = run_setup(mesobake, bunny, work, s, timeout);
        const int ok = strcmp(r.status, "ok") == 0;
        failures += !ok;
        errors += strcmp(r.status, "failed") == 0;
        char label[64];
        snprintf(label, sizeof(label), "%u^3 x %u^3", s->tile_res, s->tiles);
        fprintf(out, "%s,%u,%u,%s,", label, s->tile_res, s->tiles, r.status);
        if (ok) {
            const double eff = r.tiles * (double)s->tile_res * s->tile_res * s->tile_res;
            fprintf(out,
                    "%.3f,%.3f,%.1f,%llu,%llu,%llu,%llu,%llu,%llu,%llu,", r.seconds_total, r.wall_s, r.rss_mib,
                    (unsigned long long)r.file_bytes, (unsigned long long)(r.tile + r.splt),
                    (unsigned long long)r.colr, (unsigned long long)r.nrmm, (unsigned long long)r.memb,
                    (unsigned long long)r.mesh, (unsigned long long)(r.cell + r.other));
            fprintf(out, "%llu,%llu,%llu,%llu,%llu,", (unsigned long long)s->thesis_cell,
                    (unsigned long long)s->thesis_colour, (unsigned long long)s->thesis_normal,
                    (unsigned long long)s->thesis_memb, (unsigned long long)s->thesis_total);
            fprintf(out, "%.0f,%.0f,%.0f,%.0f,%.0f,%.0f,%.0f,%.0f,%.0f,%s,%.3f,%.3f,%.3f,\n", r.voxels_across, eff,
                    r.tiles, r.split_cells, r.cells_per_tile, r.tiles_mixed, r.cells_inside, r.cells_outside,
                    r.cells_intersected, r.voxelizer, r.tile_map_s, r.voxelize_s, r.maps_s);
        } else {
            /* Wall time and RSS up to the failure; no report, no bytes. */
            fprintf(out, ",%.3f,%.1f,,,,,,,,", r.wall_s, r.rss_mib);
            fprintf(out, "%llu,%llu,%llu,%llu,%llu,", (unsigned long long)s->thesis_cell,
                    (unsigned long long)s->thesis_colour, (unsigned long long)s->thesis_normal,
                    (unsigned long long)s->thesis_memb, (unsigned long long)s->thesis_total);
            fprintf(out, "%u,,,,,,,,,,,,,%s\n", s->tile_res * s->tiles, csv_text(r.error));
        }
        fflush(out);
    }
    fclose(out);
    rmdir(work);
    fprintf(stderr, "bench_cells_bake: wrote %s (%d of %d setups failed)\n", csv, failures, quick ? 2 : 4);
    return errors ? 1 : 0; /* a timeout is a result (its row says so), a failure is not */
}
