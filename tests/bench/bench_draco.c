/*
 * bench_draco.c — raw vs Draco MESH chunks over the bundled meshes.
 *
 *   bench_draco [CSV]
 *
 * Meshes: tests/data/{sphere,torus,spot_low_resolution,
 * blub_fish_low_resolution,saddle,wingnut}.obj, all bundled (a missing
 * one is an error). The checked-in draco.csv also has rows for the
 * Stanford bunny and armadillo, measured when this benchmark read them from
 * outside the repository; they cannot be bundled (their terms forbid
 * commercial use), so wingnut (6090 triangles) now stands for the larger
 * meshes. Each is read with the OpenMesh adapter
 * (area-weighted normals; uvs when the file has them) and stored as:
 *
 *   raw     the decoded MESH layout; "decode" = meso_file_read_chunk
 *           (CRC + copy + content checks)
 *   draco   position bits 8, 10, 12, 14, 16 (normals 10, uvs 12, speed 7);
 *           "encode" = meso_bake_mesh_chunk, "decode" = meso_file_read_chunk
 *           through the bake's Draco decoder (CRC + decode + content checks)
 *
 * Times are medians of RUNS runs. Error: per vertex (the adapter keeps the
 * vertex order) the distance between the original and the decoded position,
 * max and RMS, relative to the bounding-box diagonal. One CSV row per
 * (mesh, encoding, bits); tests/bench/plot_draco.gp draws it.
 */
#include "meso_clock.h"
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include "adapters.h"
#include "mesh_chunk.h"
#include "meso_file.h"
#include "test_util.h"

#define RUNS 9


static int cmp_double(const void* a, const void* b)
{
    double x = *(const double*)a, y = *(const double*)b;
    return (x > y) - (x < y);
}

static double median(double* t, int n)
{
    qsort(t, (size_t)n, sizeof t[0], cmp_double);
    return t[n / 2];
}

static void die(const char* what, const meso_error* err)
{
    fprintf(stderr, "bench_draco: %s%s%s\n", what, err ? ": " : "", err ? err->message : "");
    exit(1);
}

/* A one-chunk .meso file in memory holding `mc`. */
static uint8_t* one_chunk_file(const meso_mesh_chunk* mc, size_t* size)
{
    meso_writer* w;
    meso_error err;
    if (meso_writer_create(NULL, &w) != MESO_OK)
        die("writer_create", NULL);
    meso_chunk_desc d;
    memset(&d, 0, sizeof d);
    d.type = MESO_CHUNK_MESH;
    d.flags = MESO_CHUNK_FLAG_REQUIRED;
    d.object = 1;
    d.encoding = mc->encoding;
    d.decoded_size = mc->decoded_size;
    d.dtype = MESO_DTYPE_BYTES;
    if (meso_writer_add(w, &d, mc->data, mc->size, &err) != MESO_OK)
        die("writer_add", &err);
    if (meso_writer_finish(w, NULL, 0, size) != MESO_OK)
        die("writer_finish", NULL);
    uint8_t* f = malloc(*size);
    size_t n;
    if (!f || meso_writer_finish(w, f, *size, &n) != MESO_OK)
        die("writer_finish", NULL);
    meso_writer_destroy(w);
    return f;
}

/* Median time of read_chunk of chunk 0; the decoded chunk is left in *out. */
static double time_read(const uint8_t* file, size_t size, uint8_t** out, size_t* out_size)
{
    meso_decoder dec = meso_bake_draco_decoder();
    meso_open_desc desc;
    memset(&desc, 0, sizeof desc);
    desc.decoders = &dec;
    desc.decoder_count = 1;
    meso_file* f;
    meso_error err;
    if (meso_file_open_memory(file, size, &desc, &f, &err) != MESO_OK)
        die("open_memory", &err);
    const meso_chunk_info* c = meso_file_chunk(f, 0);
    uint8_t* buf = malloc((size_t)c->decoded_size);
    if (!buf)
        die("out of memory", NULL);
    memset(buf, 0, (size_t)c->decoded_size);
    double t[RUNS];
    for (int r = 0; r < RUNS; r++) {
        double s = (1e3 * meso_seconds());
        if (meso_file_read_chunk(f, 0, buf, (size_t)c->decoded_size, &err) != MESO_OK)
            die("read_chunk", &err);
        t[r] = (1e3 * meso_seconds()) - s;
    }
    *out = buf;
    *out_size = (size_t)c->decoded_size;
    meso_file_close(f);
    return median(t, RUNS);
}

/* Max and RMS position error of a decoded MESH chunk vs the original. */
static void position_error(const meso_mesh* m, const uint8_t* dec, size_t n, double diag, double* max_rel,
                           double* rms_rel)
{
    meso_mesh_view v;
    meso_error err;
    if (meso_mesh_parse(dec, n, &v, &err) != MESO_OK)
        die("mesh_parse", &err);
    if (v.layout.vertex_count != m->vertex_count || v.layout.index_count != m->triangle_count * 3u)
        die("decoded counts differ", NULL);
    double mx = 0, sum = 0;
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        double d2 = 0;
        for (int k = 0; k < 3; k++) {
            double d = (double)v.positions[3 * i + k] - (double)m->positions[3 * i + k];
            d2 += d * d;
        }
        mx = d2 > mx ? d2 : mx;
        sum += d2;
    }
    *max_rel = sqrt(mx) / diag;
    *rms_rel = sqrt(sum / m->vertex_count) / diag;
}

int main(int argc, char** argv)
{
    const char* csv = argc > 1 ? argv[1] : "draco.csv";
    static const char* bundled[] = {"sphere", "torus", "spot_low_resolution", "blub_fish_low_resolution", "saddle",
                                    "wingnut"};
    static const int bits[] = {8, 10, 12, 14, 16};
    FILE* out = fopen(csv, "w");
    if (!out)
        die("cannot write the CSV", NULL);
    fprintf(out, "mesh,vertices,triangles,encoding,position_bits,normal_bits,uv_bits,stored_bytes,bytes_rel_raw,"
                 "encode_ms,decode_ms,max_err_rel,rms_err_rel\n");
    printf("%-26s %8s %8s %6s %4s %10s %7s %9s %9s %10s %10s\n", "mesh", "verts", "tris", "enc", "bits", "bytes",
           "rel", "enc ms", "dec ms", "max err", "rms err");
    const size_t nb = sizeof bundled / sizeof bundled[0];
    for (size_t mi = 0; mi < nb; mi++) {
        char path[4096];
        const char* name = bundled[mi];
        snprintf(path, sizeof path, "%s/%s.obj", MESO_TEST_DATA, name);
        meso_mesh m;
        meso_error err;
        if (meso_openmesh_read(path, &m, NULL, &err) != MESO_OK)
            die(path, &err);
        double lo[3], hi[3];
        const double diag = meso_mesh_bounds(&m, lo, hi);

        /* Raw. */
        meso_mesh_chunk mc;
        double t[RUNS];
        for (int r = 0; r < RUNS; r++) {
            double s = (1e3 * meso_seconds());
            if (meso_bake_mesh_chunk(&m, NULL, &mc, &err) != MESO_OK)
                die("mesh_chunk raw", &err);
            t[r] = (1e3 * meso_seconds()) - s;
            if (r + 1 < RUNS)
                free(mc.data);
        }
        const double raw_enc = median(t, RUNS);
        const size_t raw_bytes = mc.size;
        size_t fsize;
        uint8_t* file = one_chunk_file(&mc, &fsize);
        free(mc.data);
        uint8_t* dec;
        size_t dn;
        const double raw_read = time_read(file, fsize, &dec, &dn);
        double emax, erms;
        position_error(&m, dec, dn, diag, &emax, &erms);
        free(dec);
        free(file);
        const char* uvbits = m.uvs ? "12" : "0";
        fprintf(out, "%s,%u,%u,raw,0,0,0,%zu,1.0,%.4f,%.4f,%.3g,%.3g\n", name, m.vertex_count, m.triangle_count,
                raw_bytes, raw_enc, raw_read, emax, erms);
        printf("%-26s %8u %8u %6s %4s %10zu %7.3f %9.3f %9.3f %10.2e %10.2e\n", name, m.vertex_count, m.triangle_count,
               "raw", "-", raw_bytes, 1.0, raw_enc, raw_read, emax, erms);

        /* Draco at each position quantisation. */
        for (size_t b = 0; b < sizeof bits / sizeof bits[0]; b++) {
            meso_draco_options opt = {bits[b], 10, 12, 7};
            for (int r = 0; r < RUNS; r++) {
                double s = (1e3 * meso_seconds());
                if (meso_bake_mesh_chunk(&m, &opt, &mc, &err) != MESO_OK)
                    die("mesh_chunk draco", &err);
                t[r] = (1e3 * meso_seconds()) - s;
                if (r + 1 < RUNS)
                    free(mc.data);
            }
            const double enc = median(t, RUNS);
            const size_t bytes = mc.size;
            file = one_chunk_file(&mc, &fsize);
            free(mc.data);
            const double dec_ms = time_read(file, fsize, &dec, &dn);
            position_error(&m, dec, dn, diag, &emax, &erms);
            free(dec);
            free(file);
            const double rel = (double)bytes / (double)raw_bytes;
            fprintf(out, "%s,%u,%u,draco,%d,%s,%s,%zu,%.5f,%.4f,%.4f,%.3g,%.3g\n", name, m.vertex_count,
                    m.triangle_count, bits[b], m.normals ? "10" : "0", uvbits, bytes, rel, enc, dec_ms, emax, erms);
            printf("%-26s %8u %8u %6s %4d %10zu %7.3f %9.3f %9.3f %10.2e %10.2e\n", name, m.vertex_count,
                   m.triangle_count, "draco", bits[b], bytes, rel, enc, dec_ms, emax, erms);
        }
        meso_mesh_free(&m);
    }
    fclose(out);
    return 0;
}
