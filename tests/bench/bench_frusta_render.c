/* bench_frusta_render — relief-mapped conical frusta on llvmpipe (issue #7):
 *
 *  frusta_vs_tess.csv  the paper's §4 comparison: the ray caster against
 *                polygon tessellations of the same relief surface
 *                (runtime/reference/frusta_tessellate.h) at growing
 *                resolution, each against the exact reference (coverage
 *                mismatch, mean hit error in
 *                pixel footprints), with memory (file bytes of the object,
 *                and the bytes a GPU holds) and draw time at 400x300 and
 *                800x600;
 *  frusta_relief_steps.csv  the relief march: uniform steps against error
 *                and cost (the knob the paper tunes);
 *  frusta_fit.csv  segments and fit error against --tolerance for a
 *                skeleton extracted from a closed mesh (when the mesh and
 *                CGAL are there).
 *
 * Scene: tests/data/saguaro.skel with the `ribs` relief, 14 ribs around,
 * depth 0.12, baked by mesobake. Timing: median of 3 draws after a warm-up,
 * glFinish included.
 * usage: bench_frusta_render RESULTS_DIR MESOBAKE DATA_DIR [FIT_MESH]
 * (FIT_MESH: meson's benchmark and run_benchmarks.sh pass the bundled
 * tests/data/spot_low_resolution.obj, run_benchmarks.sh
 * $MESO_BENCH_FIT_MESH if set; the checked-in frusta_fit.csv is of the
 * Stanford armadillo, which cannot be bundled: its terms forbid commercial
 * use) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "bench_gl.h"
#include "egl_context.h"
#include "frusta_tessellate.h"
#include "frustum_reference.h"
#include "gl_fbo.h"
#include "mesh_chunk.h"
#include "meso_rt.h"
#include "shell_scene.h"

/* Median ms of 3 draws after a warm-up; the last image is read back. */
static double time_draw(bench* b, meso_rt_object obj, meso_rt_draw_desc d, uint8_t* rgba, float* depth)
{
    const double ms = bench_median_ms(b, obj, d, 3);
    if (rgba)
        test_fbo_read(&b->fbo, rgba, depth);
    return ms;
}

static meso_rt_object load_memory(bench* b, const uint8_t* data, size_t size)
{
    meso_file* f = NULL;
    meso_error err;
    meso_rt_object obj = {0};
    if (meso_file_open_memory(data, size, NULL, &f, &err) != MESO_OK || meso_rt_load_object(b->rt, f, 1, &obj) != MESO_OK) {
        fprintf(stderr, "bench_frusta_render: cannot load a mesh object\n");
        exit(1);
    }
    meso_file_close(f);
    return obj;
}

/* A one-object .meso file in memory holding the tessellation as a MESH. */
static uint8_t* mesh_file(const meso_ref_tess_mesh* t, size_t* size)
{
    meso_mesh m = {.vertex_count = t->vertex_count, .triangle_count = t->index_count / 3, .positions = t->positions,
                   .normals = t->normals, .indices = t->indices};
    meso_mesh_chunk mc;
    meso_error err;
    meso_writer* w = NULL;
    if (meso_bake_mesh_chunk(&m, NULL, &mc, &err) != MESO_OK || meso_writer_create(NULL, &w) != MESO_OK)
        exit(1);
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_MESH};
    for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = INFINITY;
        rec.bbox_max[k] = -INFINITY;
    }
    for (uint32_t v = 0; v < t->vertex_count; ++v)
        for (int k = 0; k < 3; ++k) {
            rec.bbox_min[k] = fminf(rec.bbox_min[k], t->positions[3 * v + k]);
            rec.bbox_max[k] = fmaxf(rec.bbox_max[k], t->positions[3 * v + k]);
        }
    uint8_t objt[MESO_OBJT_RECORD_SIZE];
    meso_object_record_encode(&rec, objt);
    meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_OBJT, .flags = MESO_CHUNK_FLAG_REQUIRED}, objt,
                    sizeof(objt), &err);
    meso_writer_add(w,
                    &(meso_chunk_desc){.type = MESO_CHUNK_MESH, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1,
                                       .encoding = mc.encoding, .decoded_size = mc.decoded_size},
                    mc.data, mc.size, &err);
    size_t n = 0;
    meso_writer_finish(w, NULL, 0, &n);
    uint8_t* out = malloc(n);
    if (!out || meso_writer_finish(w, out, n, &n) != MESO_OK)
        exit(1);
    meso_writer_destroy(w);
    free(mc.data);
    *size = n;
    return out;
}

static void run(const char* cmd)
{
    fprintf(stderr, "== %s\n", cmd);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_frusta_render: command failed\n");
        exit(1);
    }
}

static double json_number(const char* path, const char* key)
{
    FILE* f = fopen(path, "r");
    if (!f)
        return NAN;
    char buf[8192];
    size_t n = fread(buf, 1, sizeof(buf) - 1, f);
    fclose(f);
    buf[n] = 0;
    char pat[128];
    snprintf(pat, sizeof(pat), "\"%s\":", key);
    const char* p = strstr(buf, pat);
    return p ? strtod(p + strlen(pat), NULL) : NAN;
}

/* Segments and fit error against the tolerance for a mesh input. */
static void fit_sweep(const char* dir, const char* mesobake, const char* mesh, const char* tmp)
{
    char cmd[8192], rep[1024], out[1024], csv[1024];
    snprintf(rep, sizeof(rep), "%s/fit.json", tmp);
    snprintf(out, sizeof(out), "%s/fit.meso", tmp);
    snprintf(cmd, sizeof(cmd), "%s frusta -i %s -o %s --report %s", mesobake, mesh, out, rep);
    if (system(cmd) != 0) {
        fprintf(stderr, "bench_frusta_render: %s: no skeleton (no CGAL, or an open mesh); fit sweep skipped\n", mesh);
        return;
    }
    const double diag = json_number(rep, "tolerance") / 0.01;
    snprintf(csv, sizeof(csv), "%s/frusta_fit.csv", dir);
    FILE* f = fopen(csv, "w");
    fprintf(f, "tolerance_rel,segments,fit_error_max_rel,fit_error_mean_rel,seconds\n");
    const double rel[] = {0.0025, 0.005, 0.01, 0.02, 0.04, 0.08};
    for (size_t i = 0; i < sizeof(rel) / sizeof(rel[0]); ++i) {
        snprintf(cmd, sizeof(cmd), "%s frusta -i %s -o %s --report %s --tolerance %g", mesobake, mesh, out, rep,
                 rel[i] * diag);
        run(cmd);
        fprintf(f, "%g,%g,%.5f,%.5f,%.2f\n", rel[i], json_number(rep, "segments"),
                json_number(rep, "fit_error_max") / diag, json_number(rep, "fit_error_mean") / diag,
                json_number(rep, "seconds_total"));
        fflush(f);
    }
    fclose(f);
    unlink(rep);
    unlink(out);
}

int main(int argc, char** argv)
{
    if (argc < 4) {
        fprintf(stderr, "usage: bench_frusta_render RESULTS_DIR MESOBAKE DATA_DIR [FIT_MESH]\n");
        return 2;
    }
    const char *dir = argv[1], *mesobake = argv[2], *data = argv[3];
    char tmp[] = "/tmp/meso_bench_frusta_XXXXXX";
    if (!mkdtemp(tmp))
        return 1;
    char path[1024], cmd[4096], csv[1024];
    snprintf(path, sizeof(path), "%s/saguaro.meso", tmp);
    snprintf(cmd, sizeof(cmd), "%s frusta -i %s/saguaro.skel -o %s --relief ribs --relief-repeat 14 --relief-depth 0.12",
             mesobake, data, path);
    run(cmd);

    bench b = {0};
    meso_egl* egl = bench_gl_open(&b, "bench_frusta_render");
    if (!egl)
        return 1;
    meso_file* f = NULL;
    meso_error err;
    meso_rt_object obj = {0};
    meso_ref_frusta ref;
    if (meso_file_open_path(path, NULL, &f, &err) != MESO_OK || meso_rt_load_object(b.rt, f, 1, &obj) != MESO_OK ||
        meso_ref_frusta_load(f, 1, &ref, &err) != MESO_OK) {
        fprintf(stderr, "bench_frusta_render: cannot load %s\n", path);
        return 1;
    }
    /* The records again, for the tessellation; and the object's bytes. */
    uint64_t object_bytes = 0;
    meso_frustum_rec* recs = NULL;
    meso_frustum_ball_rec* balls = NULL;
    uint32_t nrec = 0, nball = 0;
    {
        uint8_t *frus = NULL, *fseg = NULL, *ball = NULL;
        for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i) {
            const meso_chunk_info* c = meso_file_chunk(f, i);
            if (c->object != 1)
                continue;
            object_bytes += c->decoded_size;
            uint8_t** dst = c->type == MESO_CHUNK_FRUS ? &frus : c->type == MESO_CHUNK_FSEG ? &fseg
                                                         : c->type == MESO_CHUNK_BALL ? &ball : NULL;
            if (!dst)
                continue;
            *dst = malloc(c->decoded_size);
            if (meso_file_read_chunk(f, i, *dst, c->decoded_size, &err) != MESO_OK)
                return 1;
            if (c->type == MESO_CHUNK_FRUS)
                nrec = (uint32_t)(c->decoded_size / MESO_FRUS_RECORD_SIZE);
            if (c->type == MESO_CHUNK_BALL)
                nball = (uint32_t)(c->decoded_size / MESO_BALL_RECORD_SIZE);
        }
        recs = malloc(sizeof(*recs) * nrec);
        balls = malloc(sizeof(*balls) * (nball + 1));
        for (uint32_t i = 0; i < nrec; ++i)
            meso_frustum_rec_decode(frus + i * MESO_FRUS_RECORD_SIZE, fseg + i * MESO_FSEG_RECORD_SIZE, &recs[i]);
        for (uint32_t i = 0; i < nball; ++i)
            meso_frustum_ball_decode(ball + i * MESO_BALL_RECORD_SIZE, &balls[i]);
        free(frus);
        free(fseg);
        free(ball);
    }
    meso_file_close(f);

    double ctr[3], rad = 0;
    for (int k = 0; k < 3; ++k) {
        ctr[k] = 0.5 * (ref.bbox_min[k] + ref.bbox_max[k]);
        rad += (ref.bbox_max[k] - ref.bbox_min[k]) * (ref.bbox_max[k] - ref.bbox_min[k]);
    }
    rad = 0.5 * sqrt(rad);
    const double yaw = 30 * M_PI / 180, pitch = 10 * M_PI / 180, dist = 2.2 * rad;
    b.cam = (camera){.eye = {ctr[0] + dist * cos(pitch) * sin(yaw), ctr[1] + dist * sin(pitch),
                             ctr[2] + dist * cos(pitch) * cos(yaw)},
                     .at = {ctr[0], ctr[1], ctr[2]}, .fovy = 0.7, .zn = 0.2 * rad, .zf = 10 * rad};

    /* --- the exact reference at 400x300 ---------------------------------- */
    bench_set_size(&b, 400, 300);
    const size_t npx = (size_t)scene_w * scene_h;
    uint8_t* rgba = malloc(npx * 4);
    float* depth = malloc(sizeof(float) * npx);
    meso_ref_view v = {.width = scene_w, .height = scene_h};
    for (int i = 0; i < 16; ++i)
        v.view[i] = b.view[i], v.proj[i] = b.proj[i];
    meso_ref_image refimg;
    double t0 = meso_seconds();
    if (meso_ref_frusta_render(&ref, &v, &refimg) != MESO_OK)
        return 1;
    fprintf(stderr, "reference %dx%d: %.1f s\n", scene_w, scene_h, meso_seconds() - t0);

    /* --- relief steps ----------------------------------------------------- */
    snprintf(csv, sizeof(csv), "%s/frusta_relief_steps.csv", dir);
    FILE* rs = fopen(csv, "w");
    fprintf(rs, "relief_steps,ms,coverage_mismatch,hit_err_px,hit_gt1,colour_mae\n");
    const int steps[] = {4, 8, 16, 32, 64, 128, 256};
    for (size_t i = 0; i < sizeof(steps) / sizeof(steps[0]); ++i) {
        double ms = time_draw(&b, obj, (meso_rt_draw_desc){.frusta = {.relief_steps = steps[i]}}, rgba, depth);
        metrics m = compare(rgba, depth, &refimg, b.view, b.proj, b.cam.fovy, NULL);
        fprintf(rs, "%d,%.2f,%.5f,%.4f,%.5f,%.5f\n", steps[i], ms, m.coverage_mismatch, m.hit_err_px, m.hit_gt1,
                m.colour_mae);
        fprintf(stderr, "relief_steps %4d: %7.1f ms  cov %.4f  hit %.3f px  >1px %.4f  colour %.4f\n", steps[i], ms,
                m.coverage_mismatch, m.hit_err_px, m.hit_gt1, m.colour_mae);
        fflush(rs);
    }
    fclose(rs);

    /* --- frusta against tessellations ------------------------------------- */
    snprintf(csv, sizeof(csv), "%s/frusta_vs_tess.csv", dir);
    FILE* vt = fopen(csv, "w");
    fprintf(vt, "renderer,grid_u,triangles,file_bytes,gpu_bytes,ms_400x300,ms_800x600,coverage_mismatch,hit_err_px,"
                "hit_gt1\n");
    /* The ray caster: GPU bytes are the records as uploaded (about the file's
     * payloads) plus the relief texture: report the object's payload bytes. */
    double ms_small = time_draw(&b, obj, (meso_rt_draw_desc){0}, rgba, depth);
    metrics mf = compare(rgba, depth, &refimg, b.view, b.proj, b.cam.fovy, NULL);
    bench_set_size(&b, 800, 600);
    double ms_big = time_draw(&b, obj, (meso_rt_draw_desc){0}, NULL, NULL);
    bench_set_size(&b, 400, 300);
    fprintf(vt, "frusta,0,0,%llu,%llu,%.2f,%.2f,%.5f,%.4f,%.5f\n", (unsigned long long)object_bytes,
            (unsigned long long)object_bytes, ms_small, ms_big, mf.coverage_mismatch, mf.hit_err_px, mf.hit_gt1);
    fprintf(stderr, "frusta: %llu bytes, %.1f / %.1f ms, cov %.4f, hit %.3f px\n", (unsigned long long)object_bytes,
            ms_small, ms_big, mf.coverage_mismatch, mf.hit_err_px);
    const uint32_t grids[] = {8, 16, 32, 64, 128, 256, 512};
    for (size_t g = 0; g < sizeof(grids) / sizeof(grids[0]); ++g) {
        meso_ref_tess_mesh tm;
        if (!meso_ref_frusta_tessellate(recs, nrec, balls, nball, &ref.relief.height, grids[g], &tm))
            return 1;
        size_t fsize = 0;
        uint8_t* file = mesh_file(&tm, &fsize);
        meso_rt_object mo = load_memory(&b, file, fsize);
        const uint64_t gpu = (uint64_t)tm.vertex_count * 24u + (uint64_t)tm.index_count * 4u;
        double ms1 = time_draw(&b, mo, (meso_rt_draw_desc){0}, rgba, depth);
        metrics mt = compare(rgba, depth, &refimg, b.view, b.proj, b.cam.fovy, NULL);
        bench_set_size(&b, 800, 600);
        double ms2 = time_draw(&b, mo, (meso_rt_draw_desc){0}, NULL, NULL);
        bench_set_size(&b, 400, 300);
        fprintf(vt, "tessellation,%u,%u,%zu,%llu,%.2f,%.2f,%.5f,%.4f,%.5f\n", grids[g], tm.index_count / 3, fsize,
                (unsigned long long)gpu, ms1, ms2, mt.coverage_mismatch, mt.hit_err_px, mt.hit_gt1);
        fprintf(stderr, "tessellation %3u: %8u triangles, %9zu bytes, %.1f / %.1f ms, cov %.4f, hit %.3f px\n",
                grids[g], tm.index_count / 3, fsize, ms1, ms2, mt.coverage_mismatch, mt.hit_err_px);
        fflush(vt);
        meso_rt_release_object(b.rt, mo);
        free(file);
        meso_ref_tess_free(&tm);
    }
    fclose(vt);

    if (argc > 4)
        fit_sweep(dir, mesobake, argv[4], tmp);

    unlink(path);
    rmdir(tmp);
    meso_ref_image_free(&refimg);
    meso_ref_frusta_free(&ref);
    free(recs);
    free(balls);
    free(rgba);
    free(depth);
    meso_rt_release_object(b.rt, obj);
    test_fbo_destroy(&b.fbo);
    meso_rt_destroy(b.rt);
    meso_egl_destroy(egl);
    return 0;
}
