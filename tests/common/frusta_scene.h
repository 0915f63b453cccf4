/* frusta_scene.h — what the frusta GL test and the frusta benchmark share
 * (header-only test code): a one-object frusta file (FORMAT.md §7.2 kind 4,
 * object id 1) in memory, baked from SWC text or an SWC path with
 * mesobake's own code (skeleton → frustum model → records,
 * bake/frusta_chunks.h) and the format library's writer, optionally with a
 * relief map, a colour map and with the defects the malformed-input tests
 * need. */
#ifndef MESO_TEST_FRUSTA_SCENE_H
#define MESO_TEST_FRUSTA_SCENE_H

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frusta_chunks.h"
#include "frustum_model.h"
#include "meso_file.h"
#include "skeleton_swc.h"

#define FRUSTA_SCENE_CHECK(x, msg)                                            \
    do {                                                                      \
        if (!(x)) {                                                           \
            fprintf(stderr, "FAILED: %s: %s (%s:%d)\n", #x, msg, __FILE__, __LINE__); \
            abort();                                                          \
        }                                                                     \
    } while (0)

typedef struct frusta_file_opts {
    double depth;             /* relief depth (world units); 0: none */
    double u_repeat;          /* relief tiles around the axis */
    const uint8_t* relief;    /* RELF texels (U8, relief_w x relief_h, s fastest), or NULL */
    uint32_t relief_w, relief_h;
    uint32_t drop;            /* a chunk type to leave out */
    int frus_short;           /* write one FRUS record fewer than FSEG */
    int relief_f32;           /* RELF as F32 (not a dtype §7.2 allows) */
    int bad_node;             /* frustum 0's node1 past the end of SKEL */
    int keep_crossing_caps;   /* bake with the paper's joint planes even where caps cross */
    double twist;             /* degrees per unit length (mesobake frusta --twist); 0: none */
    const uint8_t* color;     /* COLR texels (RGBA8 sRGB, color_w x color_h, s fastest, row 0 at t = 0), or NULL */
    uint32_t color_w, color_h;
    uint32_t color_depth;     /* COLR dims[2] (a defect when > 1; 0: 1), color_h divisible by it */
    int color_twice;          /* a second COLR chunk (lod 1; a defect) */
} frusta_file_opts;

/* An SWC path (starting with '/') or SWC text. */
static inline meso_skeleton frusta_scene_skeleton(const char* swc)
{
    meso_skeleton s;
    meso_error err;
    meso_result r = swc[0] == '/' ? meso_skeleton_load_swc(swc, &s, &err)
                                  : meso_skeleton_parse_swc(swc, strlen(swc), &s, &err);
    FRUSTA_SCENE_CHECK(r == MESO_OK, err.message);
    return s;
}

static inline void frusta_scene_add(meso_writer* w, uint32_t type, const void* data, size_t size, uint16_t dtype,
                                    uint32_t d0, uint32_t d1)
{
    meso_error err;
    const meso_chunk_desc cd = {.type = type,
                                .flags = type == MESO_CHUNK_RELF ? 0 : MESO_CHUNK_FLAG_REQUIRED,
                                .object = type == MESO_CHUNK_OBJT ? 0 : 1,
                                .dtype = dtype,
                                .components = 1,
                                .dims = {d0, d1, 1}};
    FRUSTA_SCENE_CHECK(meso_writer_add(w, &cd, data, size, &err) == MESO_OK, err.message);
}

/* The file's bytes (malloc'd) and their count. */
static inline uint8_t* frusta_file(const char* swc, const frusta_file_opts* o, size_t* size)
{
    meso_skeleton sk = frusta_scene_skeleton(swc);
    meso_frustum_model m;
    meso_error err;
    const meso_frustum_options mo = {.keep_cap_intersections = o->keep_crossing_caps,
                                     .twist_per_length = o->twist * (3.14159265358979323846 / 180)};
    FRUSTA_SCENE_CHECK(meso_frustum_model_build(&sk, &mo, &m, &err) == MESO_OK, err.message);
    const meso_frusta_relief_params rp = {.depth = o->depth, .u_repeat = o->u_repeat};
    meso_frusta_object fo;
    FRUSTA_SCENE_CHECK(meso_frusta_object_build(&sk, &m, &rp, &fo, &err) == MESO_OK, err.message);
    if (o->bad_node)
        fo.recs[0].node[1] = fo.node_count + 3;
    uint8_t *frus = NULL, *fseg = NULL, *ball = NULL;
    FRUSTA_SCENE_CHECK(meso_frusta_object_encode(&fo, &frus, &fseg, &ball, &err) == MESO_OK, err.message);
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_FRUSTA};
    memcpy(rec.bbox_min, fo.bbox_min, sizeof(rec.bbox_min));
    memcpy(rec.bbox_max, fo.bbox_max, sizeof(rec.bbox_max));
    snprintf(rec.name, sizeof(rec.name), "frusta");
    uint8_t objt[64];
    meso_object_record_encode(&rec, objt);
    meso_writer* w = NULL;
    FRUSTA_SCENE_CHECK(meso_writer_create(NULL, &w) == MESO_OK, "writer");
    frusta_scene_add(w, MESO_CHUNK_OBJT, objt, 64, MESO_DTYPE_BYTES, 1, 1);
    if (o->drop != MESO_CHUNK_SKEL)
        frusta_scene_add(w, MESO_CHUNK_SKEL, fo.skel, (size_t)MESO_SKEL_RECORD_SIZE * fo.node_count,
                         MESO_DTYPE_BYTES, fo.node_count, 1);
    const uint32_t nfrus = o->frus_short ? fo.count - 1 : fo.count;
    if (o->drop != MESO_CHUNK_FRUS)
        frusta_scene_add(w, MESO_CHUNK_FRUS, frus, (size_t)MESO_FRUS_RECORD_SIZE * nfrus, MESO_DTYPE_BYTES, nfrus, 1);
    if (o->drop != MESO_CHUNK_FSEG)
        frusta_scene_add(w, MESO_CHUNK_FSEG, fseg, (size_t)MESO_FSEG_RECORD_SIZE * fo.count, MESO_DTYPE_BYTES,
                         fo.count, 1);
    if (fo.ball_count)
        frusta_scene_add(w, MESO_CHUNK_BALL, ball, (size_t)MESO_BALL_RECORD_SIZE * fo.ball_count, MESO_DTYPE_BYTES,
                         fo.ball_count, 1);
    const size_t texels = (size_t)o->relief_w * o->relief_h;
    if (o->relief && o->relief_f32) {
        float* v = malloc(sizeof(float) * texels);
        for (size_t i = 0; i < texels; ++i)
            v[i] = o->relief[i] / 255.0f;
        frusta_scene_add(w, MESO_CHUNK_RELF, v, sizeof(float) * texels, MESO_DTYPE_F32, o->relief_w, o->relief_h);
        free(v);
    } else if (o->relief) {
        frusta_scene_add(w, MESO_CHUNK_RELF, o->relief, texels, MESO_DTYPE_U8, o->relief_w, o->relief_h);
    }
    for (int k = 0; o->color && k <= (o->color_twice ? 1 : 0); ++k) {
        const uint32_t depth = o->color_depth ? o->color_depth : 1;
        const meso_chunk_desc cd = {.type = MESO_CHUNK_COLR,
                                    .object = 1,
                                    .lod = (uint16_t)k,
                                    .dtype = MESO_DTYPE_U8,
                                    .components = 4,
                                    .dims = {o->color_w, o->color_h / depth, depth}};
        FRUSTA_SCENE_CHECK(meso_writer_add(w, &cd, o->color, 4 * (size_t)o->color_w * o->color_h, &err) == MESO_OK,
                           err.message);
    }
    size_t need = 0;
    meso_writer_finish(w, NULL, 0, &need);
    uint8_t* buf = malloc(need);
    FRUSTA_SCENE_CHECK(buf && meso_writer_finish(w, buf, need, size) == MESO_OK, "writer finish");
    meso_writer_destroy(w);
    free(frus);
    free(fseg);
    free(ball);
    meso_frusta_object_free(&fo);
    meso_frustum_model_free(&m);
    meso_skeleton_free(&sk);
    return buf;
}

/* The records of object 1 (FRUS + FSEG, BALL) decoded from a file, for
 * posing them on the host as a runtime would (frusta_pose.h). Arrays are
 * malloc'd; *balls is never NULL. */
static inline void frusta_file_records(const uint8_t* file, size_t size, meso_frustum_rec** recs, uint32_t* count,
                                       meso_frustum_ball_rec** balls, uint32_t* ball_count)
{
    meso_file* f = NULL;
    meso_error err;
    FRUSTA_SCENE_CHECK(meso_file_open_memory(file, size, NULL, &f, &err) == MESO_OK, err.message);
    const uint32_t types[3] = {MESO_CHUNK_FRUS, MESO_CHUNK_FSEG, MESO_CHUNK_BALL};
    uint8_t* buf[3] = {NULL, NULL, NULL};
    size_t n[3] = {0, 0, 0};
    for (uint32_t i = 0; i < meso_file_chunk_count(f); ++i)
        for (int k = 0; k < 3; ++k)
            if (meso_file_chunk(f, i)->type == types[k] && meso_file_chunk(f, i)->object == 1) {
                n[k] = (size_t)meso_file_chunk(f, i)->decoded_size;
                buf[k] = malloc(n[k]);
                FRUSTA_SCENE_CHECK(buf[k] && meso_file_read_chunk(f, i, buf[k], n[k], &err) == MESO_OK, err.message);
            }
    meso_file_close(f);
    *count = (uint32_t)(n[0] / MESO_FRUS_RECORD_SIZE);
    *ball_count = (uint32_t)(n[2] / MESO_BALL_RECORD_SIZE);
    *recs = malloc(sizeof(**recs) * (*count + 1));
    *balls = malloc(sizeof(**balls) * (*ball_count + 1));
    FRUSTA_SCENE_CHECK(*recs && *balls && n[1] / MESO_FSEG_RECORD_SIZE == *count, "records");
    for (uint32_t i = 0; i < *count; ++i)
        meso_frustum_rec_decode(buf[0] + (size_t)MESO_FRUS_RECORD_SIZE * i, buf[1] + (size_t)MESO_FSEG_RECORD_SIZE * i,
                                &(*recs)[i]);
    for (uint32_t b = 0; b < *ball_count; ++b)
        meso_frustum_ball_decode(buf[2] + (size_t)MESO_BALL_RECORD_SIZE * b, &(*balls)[b]);
    for (int k = 0; k < 3; ++k)
        free(buf[k]);
}

#endif
