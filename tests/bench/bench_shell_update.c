/*
 * bench_shell_update.c — incremental shell re-bakes (`mesobake shell
 * --update`, bake/shell_update.c) against full re-bakes of the same edited
 * mesh: time against edit size.
 *
 *   bench_shell_update OUTDIR [MESH...]   -> OUTDIR/shell_update.csv
 *
 * Meshes: the arguments, default tests/data/spot_uv.obj and
 * blub_fish_low_resolution.obj. Per mesh, exterior hybrid shells (the CLI's
 * defaults) at 2 % and 5 % of the diagonal; the edit is a smooth cosine bump
 * (height 0.3 h, away from the centroid) over the fraction f ∈ {0.1 %, 1 %,
 * 10 %} of the vertices nearest to vertex n/3. Each of the full re-bake and
 * the update is run RUNS times on THREADS threads through meso_bake_shell
 * (no file I/O but OLD's read), median wall time reported. Columns: the
 * report's vertices_moved / vertices_recomputed, both medians and their
 * ratio, both shells' validity, and the median process CPU seconds of each
 * (all threads: less noisy than wall time on a shared machine). Stdout also
 * has the update's stages (the report's seconds_*, run with the median
 * wall time; MESO_BENCH_VERBOSE=1 prints every bake's stage lines).
 */
#include "test_util.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mesh_bump.h"
#include "meso_bake.h"
#include "meso_clock.h"

#include <time.h>

enum { RUNS = 3, THREADS = 2 };

static void die(const char* what, const meso_error* err)
{
    fprintf(stderr, "bench_shell_update: %s: %s\n", what, err ? err->message : "");
    exit(1);
}


/* MESO_BENCH_VERBOSE=1: the bakes' stage lines (mesobake -v's). */
static void print_stage(void* user, const meso_bake_progress* p)
{
    (void)user;
    if (p->event == MESO_BAKE_EVENT_STAGE && p->message)
        printf("    %s\n", p->message);
}

static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Median wall seconds of RUNS bakes with options o (*cpu: the median CPU
 * seconds); *rep: the report of the run with the median wall time. */
static double timed(const meso_bake_shell_options* o, meso_bake_shell_report* rep, double* cpu, const char* write_to)
{
    double t[RUNS], c[RUNS], sorted[RUNS];
    meso_bake_shell_report reps[RUNS];
    for (int k = 0; k < RUNS; ++k) {
        meso_bake_output* out = NULL;
        meso_error err = {0};
        const double t0 = meso_seconds(), c0 = cpu_seconds();
        if (meso_bake_shell(o, &out, &reps[k], &err) != MESO_OK)
            die("bake", &err);
        t[k] = meso_seconds() - t0;
        c[k] = cpu_seconds() - c0;
        if (write_to && k == 0 && meso_bake_output_write_file(out, write_to, &err) != MESO_OK)
            die(write_to, &err);
        meso_bake_output_free(out);
    }
    memcpy(sorted, t, sizeof(t));
    qsort(sorted, RUNS, sizeof(sorted[0]), mesh_bump_cmp);
    for (int k = 0; k < RUNS; ++k)
        if (t[k] == sorted[RUNS / 2])
            *rep = reps[k];
    qsort(c, RUNS, sizeof(c[0]), mesh_bump_cmp);
    if (cpu)
        *cpu = c[RUNS / 2];
    return sorted[RUNS / 2];
}


int main(int argc, char** argv)
{
    if (argc < 2) {
        fputs("usage: bench_shell_update OUTDIR [MESH...]\n", stderr);
        return 1;
    }
    char path[4200], old_path[4200];
    snprintf(path, sizeof(path), "%s/shell_update.csv", argv[1]);
    snprintf(old_path, sizeof(old_path), "%s/.shell_update_old.meso", argv[1]);
    FILE* csv = fopen(path, "w");
    if (!csv)
        die(path, NULL);
    fprintf(csv, "mesh,vertices,thickness_rel,edit_fraction,vertices_moved,vertices_recomputed,full_s,update_s,"
                 "ratio,full_valid,update_valid,full_cpu_s,update_cpu_s\n");
    const char* defaults[] = {test_data("spot_uv.obj"), NULL};
    char spot[4096];
    snprintf(spot, sizeof(spot), "%s", defaults[0]);
    defaults[0] = spot;
    defaults[1] = test_data("blub_fish_low_resolution.obj");
    const char* const* meshes = argc > 2 ? (const char* const*)argv + 2 : defaults;
    const int mesh_count = argc > 2 ? argc - 2 : 2;
    static const double rels[] = {0.02, 0.05}, fractions[] = {0.001, 0.01, 0.1};
    for (int mi = 0; mi < mesh_count; ++mi) {
        meso_mesh m;
        meso_error err = {0};
        if (meso_bake_load_mesh(meshes[mi], NULL, &m, NULL, &err) != MESO_OK)
            die(meshes[mi], &err);
        const char* name = strrchr(meshes[mi], '/') ? strrchr(meshes[mi], '/') + 1 : meshes[mi];
        float* pos = malloc(sizeof(float) * 3 * m.vertex_count);
        for (size_t ri = 0; ri < sizeof(rels) / sizeof(rels[0]); ++ri) {
            meso_bake_shell_options o = meso_bake_shell_defaults();
            o.common.threads = THREADS;
            if (getenv("MESO_BENCH_VERBOSE"))
                o.common.progress = print_stage;
            o.mesh = &m;
            o.thickness_rel = rels[ri];
            meso_bake_shell_report old_rep;
            timed(&o, &old_rep, NULL, old_path);
            o.thickness = old_rep.thickness;
            for (size_t fi = 0; fi < sizeof(fractions) / sizeof(fractions[0]); ++fi) {
                memcpy(pos, m.positions, sizeof(float) * 3 * m.vertex_count);
                const uint32_t count = (uint32_t)fmax(1.0, fractions[fi] * m.vertex_count);
                mesh_bump(pos, m.vertex_count, m.vertex_count / 3, count, 0.3 * old_rep.thickness);
                meso_mesh e = m;
                e.positions = pos;
                o.mesh = &e;
                o.update = NULL;
                meso_bake_shell_report full, upd;
                double cf = 0, cu = 0;
                const double tf = timed(&o, &full, &cf, NULL);
                o.update = old_path;
                const double tu = timed(&o, &upd, &cu, NULL);
                o.mesh = &m;
                o.update = NULL;
                const int full_valid = !full.inverted_prisms && !full.offset_self_intersections &&
                                       !full.offset_base_intersections;
                const int upd_valid = !upd.inverted_prisms && !upd.offset_self_intersections &&
                                      !upd.offset_base_intersections;
                fprintf(csv, "%s,%u,%g,%g,%u,%u,%.3f,%.3f,%.3f,%d,%d,%.3f,%.3f\n", name, m.vertex_count, rels[ri],
                        fractions[fi], upd.vertices_moved, upd.vertices_recomputed, tf, tu, tu / tf, full_valid,
                        upd_valid, cf, cu);
                fflush(csv);
                printf("%s %g %g: moved %u recomputed %u of %u, full %.2f s update %.2f s (%.2f)\n", name, rels[ri],
                       fractions[fi], upd.vertices_moved, upd.vertices_recomputed, m.vertex_count, tf, tu, tu / tf);
                printf("  cpu: full %.2f s update %.2f s (%.2f)\n", cf, cu, cu / cf);
                const meso_bake_shell_report* st[2] = {&full, &upd};
                for (int k = 0; k < 2; ++k)
                    printf("  %s: load %.3f topology %.3f check %.3f texture %.3f field %.3f directors %.3f "
                           "(checks %.3f) repair %.3f validate %.3f allowed %.3f assemble %.3f\n",
                           k ? "update" : "full", st[k]->seconds_load, st[k]->seconds_topology, st[k]->seconds_check,
                           st[k]->seconds_texture, st[k]->seconds_field, st[k]->seconds_directors,
                           st[k]->seconds_directors_checks, st[k]->seconds_repair, st[k]->seconds_validate,
                           st[k]->seconds_allowed, st[k]->seconds_assemble);
            }
        }
        free(pos);
        meso_mesh_free(&m);
    }
    remove(old_path);
    fclose(csv);
    return 0;
}
