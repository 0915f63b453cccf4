/*
 * ref_common.c — chunk reading, camera and image helpers of the CPU
 * references (ref_common.h).
 */
#include "ref_common.h"

#include <pthread.h>
#include <unistd.h>

#include "mat4_inverse.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* >>files ------------------------------------------------------------------ */

meso_result mesoi_ref_fail(meso_error* err, meso_result r, const char* what, uint32_t id, const char* msg)
{
    if (err) {
        memset(err, 0, sizeof(*err));
        err->result = r;
        err->offset = UINT64_MAX;
        err->chunk = -1;
        snprintf(err->message, sizeof(err->message), "%s %u: %s", what, id, msg);
    }
    return r;
}

meso_result mesoi_ref_object(meso_file* f, uint32_t id, uint32_t kind, const char* what, meso_object_record* out,
    meso_error* err)
{
    uint32_t count = 0;
    meso_result r = meso_file_objects(f, NULL, 0, &count, err);
    if (r != MESO_OK)
        return r;
    meso_object_record* recs = count ? malloc(sizeof(*recs) * count) : NULL;
    if (count && !recs)
        return mesoi_ref_fail(err, MESO_ERR_OUT_OF_MEMORY, what, id, "out of memory");
    if ((r = meso_file_objects(f, recs, count, &count, err)) != MESO_OK) {
        free(recs);
        return r;
    }
    const meso_object_record* rec = NULL;
    for (uint32_t i = 0; i < count; ++i)
        if (recs[i].id == id)
            rec = &recs[i];
    if (!rec)
        r = mesoi_ref_fail(err, MESO_ERR_NOT_FOUND, what, id, "no such object in the OBJT table");
    else if (rec->kind != kind) {
        char msg[64];
        snprintf(msg, sizeof(msg), "not a %s object (kind %u)", what, kind);
        r = mesoi_ref_fail(err, MESO_ERR_INVALID_ARG, what, id, msg);
    } else
        *out = *rec;
    free(recs);
    return r;
}

meso_result mesoi_ref_read_whole(meso_file* f, int32_t ci, void** out, size_t* size, meso_error* err)
{
    const meso_chunk_info* c = ci >= 0 ? meso_file_chunk(f, (uint32_t)ci) : NULL;
    if (!c)
        return MESO_ERR_NOT_FOUND;
    if (c->decoded_size == 0 || c->decoded_size > (uint64_t)(SIZE_MAX / 2))
        return MESO_ERR_UNSUPPORTED;
    void* data = malloc((size_t)c->decoded_size);
    if (!data)
        return MESO_ERR_OUT_OF_MEMORY;
    const meso_result r = meso_file_read_chunk(f, (uint32_t)ci, data, (size_t)c->decoded_size, err);
    if (r != MESO_OK) {
        free(data);
        return r;
    }
    *out = data;
    *size = (size_t)c->decoded_size;
    return MESO_OK;
}

meso_result mesoi_ref_read_unorm(meso_file* f, int32_t ci, float** values, meso_error* err)
{
    const meso_chunk_info* tc = meso_file_chunk(f, (uint32_t)ci);
    if (!tc)
        return MESO_ERR_NOT_FOUND;
    const uint32_t es = tc->dtype == MESO_DTYPE_U8 ? 1 : tc->dtype == MESO_DTYPE_U16 ? 2 : 0;
    const uint64_t texels = (uint64_t)tc->dims[0] * tc->dims[1] * tc->dims[2];
    if (es == 0 || tc->components != 1 || tc->decoded_size != texels * es || texels == 0 ||
        texels > (uint64_t)(SIZE_MAX / sizeof(float)))
        return MESO_ERR_UNSUPPORTED;
    void* raw = NULL;
    size_t size = 0;
    meso_result r = mesoi_ref_read_whole(f, ci, &raw, &size, err);
    if (r != MESO_OK)
        return r;
    float* v = malloc(sizeof(float) * (size_t)texels);
    if (!v) {
        free(raw);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    for (size_t i = 0; i < (size_t)texels; ++i) {
        if (es == 1) {
            v[i] = (float)(((const uint8_t*)raw)[i] / 255.0);
        } else {
            const uint8_t* b = (const uint8_t*)raw + 2 * i; /* little-endian on disk */
            v[i] = (float)((unsigned)(b[0] | (b[1] << 8)) / 65535.0);
        }
    }
    free(raw);
    *values = v;
    return MESO_OK;
}

/* >>camera ----------------------------------------------------------------- */

/* Column-major 4×4: c = a · b. */
static void mat_mul(const double a[16], const double b[16], double c[16])
{
    for (int col = 0; col < 4; ++col)
        for (int row = 0; row < 4; ++row) {
            double s = 0;
            for (int k = 0; k < 4; ++k)
                s += a[4 * k + row] * b[4 * col + k];
            c[4 * col + row] = s;
        }
}

static void mat_apply(const double m[16], const double x[4], double y[4])
{
    for (int r = 0; r < 4; ++r)
        y[r] = m[r] * x[0] + m[4 + r] * x[1] + m[8 + r] * x[2] + m[12 + r] * x[3];
}

int mesoi_ref_camera_init(const meso_ref_view* v, mesoi_ref_camera* c)
{
    double model[16], pv[16];
    int model_zero = 1;
    for (int i = 0; i < 16; ++i)
        model_zero &= v->model[i] == 0;
    for (int i = 0; i < 16; ++i)
        model[i] = model_zero ? (i % 5 == 0) : v->model[i];
    mat_mul(v->proj, v->view, pv);
    mat_mul(pv, model, c->mvp);
    if (!meso_mat4_inverse(c->mvp, c->inv))
        return 0;
    double l[3] = {v->light_dir[0], v->light_dir[1], v->light_dir[2]};
    if (l[0] == 0 && l[1] == 0 && l[2] == 0) {
        l[0] = 0.3;
        l[1] = 0.8;
        l[2] = 0.5;
    }
    for (int i = 0; i < 3; ++i) /* transpose(mat3(model)) · l */
        c->light[i] = model[4 * i] * l[0] + model[4 * i + 1] * l[1] + model[4 * i + 2] * l[2];
    const double ll = sqrt(c->light[0] * c->light[0] + c->light[1] * c->light[1] + c->light[2] * c->light[2]);
    for (int i = 0; i < 3; ++i)
        c->light[i] = ll > 0 ? c->light[i] / ll : 0;
    const int no_albedo = v->albedo[0] == 0 && v->albedo[1] == 0 && v->albedo[2] == 0;
    const double def_albedo[3] = {0.80, 0.74, 0.66};
    for (int i = 0; i < 3; ++i)
        c->albedo[i] = no_albedo ? def_albedo[i] : v->albedo[i];
    return 1;
}

void mesoi_ref_pixel_ray(const mesoi_ref_camera* c, int x, int y, int W, int H, double o[3], double d[3])
{
    const double ndc_x = (2.0 * x + 1) / W - 1, ndc_y = (2.0 * y + 1) / H - 1;
    const double cn[4] = {ndc_x, ndc_y, -1, 1}, cf[4] = {ndc_x, ndc_y, 1, 1};
    double on[4], of[4];
    mat_apply(c->inv, cn, on);
    mat_apply(c->inv, cf, of);
    for (int k = 0; k < 3; ++k) {
        o[k] = on[k] / on[3];
        d[k] = of[k] / of[3] - o[k];
    }
}

float mesoi_ref_depth(const mesoi_ref_camera* c, const double p[3])
{
    const double p4[4] = {p[0], p[1], p[2], 1};
    double clip[4];
    mat_apply(c->mvp, p4, clip);
    return (float)(0.5 * clip[2] / clip[3] + 0.5);
}

void mesoi_ref_shade(const mesoi_ref_camera* c, const double d[3], const double n_in[3], double w, float rgb[3],
    float nrm[3])
{
    mesoi_ref_shade_albedo(c, c->albedo, d, n_in, w, rgb, nrm);
}

void mesoi_ref_shade_albedo(const mesoi_ref_camera* c, const double albedo[3], const double d[3], const double n_in[3],
                            double w, float rgb[3], float nrm[3])
{
    double n[3] = {n_in[0], n_in[1], n_in[2]};
    const double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    if (nl > 0)
        for (int i = 0; i < 3; ++i)
            n[i] /= nl;
    if (n[0] * d[0] + n[1] * d[1] + n[2] * d[2] > 0)
        for (int i = 0; i < 3; ++i)
            n[i] = -n[i];
    const double ndl = n[0] * c->light[0] + n[1] * c->light[1] + n[2] * c->light[2];
    const double k = (0.25 + 0.75 * w) * (0.15 + 0.85 * fmax(0.0, ndl));
    for (int i = 0; i < 3; ++i) {
        rgb[i] = (float)(albedo[i] * k);
        nrm[i] = (float)n[i];
    }
}

/* >>images ----------------------------------------------------------------- */

void meso_ref_image_free(meso_ref_image* img)
{
    if (!img)
        return;
    free(img->rgb);
    free(img->depth);
    free(img->coverage);
    free(img->hit);
    free(img->normal);
    free(img->albedo);
    memset(img, 0, sizeof(*img));
}

meso_result mesoi_ref_image_alloc(meso_ref_image* out, int W, int H)
{
    memset(out, 0, sizeof(*out));
    const size_t npx = (size_t)W * (size_t)H;
    out->rgb = malloc(sizeof(float) * 3 * npx);
    out->depth = malloc(sizeof(float) * npx);
    out->coverage = malloc(npx);
    out->hit = malloc(sizeof(float) * 3 * npx);
    out->normal = malloc(sizeof(float) * 3 * npx);
    out->albedo = calloc(3 * npx, sizeof(float));
    if (!out->rgb || !out->depth || !out->coverage || !out->hit || !out->normal || !out->albedo) {
        meso_ref_image_free(out);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    out->width = W;
    out->height = H;
    return MESO_OK;
}

void mesoi_ref_image_miss(meso_ref_image* img, size_t px)
{
    img->rgb[3 * px] = img->rgb[3 * px + 1] = img->rgb[3 * px + 2] = 0.0f;
    img->depth[px] = 1.0f;
    img->coverage[px] = 0;
    img->hit[3 * px] = img->hit[3 * px + 1] = img->hit[3 * px + 2] = NAN;
    img->normal[3 * px] = img->normal[3 * px + 1] = img->normal[3 * px + 2] = 0.0f;
    img->albedo[3 * px] = img->albedo[3 * px + 1] = img->albedo[3 * px + 2] = 0.0f;
}

/* >>threads ---------------------------------------------------------------- */

typedef struct row_job {
    void (*row)(const void* user, int y);
    const void* user;
    int first, step, height;
} row_job;

static void* row_worker(void* arg)
{
    const row_job* j = arg;
    for (int y = j->first; y < j->height; y += j->step)
        j->row(j->user, y);
    return NULL;
}

#define ROWS_MAX_THREADS 64

void mesoi_ref_rows(int height, int threads_wanted, void (*row)(const void* user, int y), const void* user)
{
    long threads = threads_wanted > 0 ? threads_wanted : sysconf(_SC_NPROCESSORS_ONLN);
    threads = threads < 1 ? 1 : threads > ROWS_MAX_THREADS ? ROWS_MAX_THREADS : threads;
    if (threads > height)
        threads = height > 0 ? height : 1;
    pthread_t tid[ROWS_MAX_THREADS];
    row_job jobs[ROWS_MAX_THREADS];
    int started[ROWS_MAX_THREADS] = {0};
    for (int k = 0; k < threads; ++k)
        jobs[k] = (row_job){row, user, k, (int)threads, height};
    for (int k = 1; k < threads; ++k)
        started[k] = pthread_create(&tid[k], NULL, row_worker, &jobs[k]) == 0;
    row_worker(&jobs[0]);
    for (int k = 1; k < threads; ++k) {
        if (started[k])
            pthread_join(tid[k], NULL);
        else
            row_worker(&jobs[k]); /* could not start a thread: do its rows here */
    }
}
