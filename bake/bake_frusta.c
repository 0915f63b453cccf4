/*
 * bake_frusta.c — meso_bake_frusta (`mesobake frusta`) and
 * meso_bake_skeleton_load: a skeleton (SWC, the text format of
 * skeleton_swc.h, or one extracted from a closed mesh) skinned with conical
 * frusta (relief-mapped-conical-frusta.md §2, bake/frustum_model.h), with an
 * optional relief map (§3) and colour map (sampled at the relief
 * coordinates), as one .meso frusta object: SKEL, FRUS, FSEG, BALL, RELF
 * and COLR (FORMAT.md §7.2 kind 4); with levels (the default), native
 * relief levels (the relief map halved, relief_levels below), coarser
 * skeletons (frusta_skeleton_levels.h), then a triangle tessellation (a
 * MESH, frusta_standin.h) and its simplifications, and LODS.
 */
#include "bake_internal.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "color_map.h"
#include "frusta_chunks.h"
#include "frusta_skeleton_levels.h"
#include "frusta_standin.h"
#include "height_field_levels.h"
#include "standin_levels.h"
#include "meso_clock.h"
#include "frustum_model.h"
#include "memory_budget.h"
#include "mesh_chunk.h"
#include "skeleton_swc.h"
#include "surface_distance.h"
#include "texture_function.h"
#if MESO_HAVE_CGAL
#include "skeleton_from_mesh.h"
#endif

/* A loaded skeleton keeps what a bake of it reports and records: where it
 * came from (the path, for names and META provenance) and the load's info. */
struct meso_bake_skeleton {
    meso_skeleton sk;
    meso_bake_skeleton_info info;
    char* path;
};

meso_bake_frusta_options meso_bake_frusta_defaults(void)
{
    return (meso_bake_frusta_options){.max_joint_angle = 150, .relief_repeat = 1};
}

static int is_mesh_path(const char* p)
{
    static const char* const ext[] = {".obj", ".off", ".ply", ".stl", ".om", ".drc", ".gltf", ".glb"};
    for (size_t i = 0; i < sizeof(ext) / sizeof(ext[0]); ++i)
        if (mesoi_has_suffix(p, ext[i]))
            return 1;
    return 0;
}

/* Limits up front: a skeleton file's nodes (at most its lines) against the
 * budget before it is read and parsed (memory_budget.h). */
static meso_result check_skeleton_size(const mesoi_bake_run* run, const char* path, meso_error* err)
{
    uint64_t bytes = 0, lines = 0;
    meso_error ignored = {0};
    if (meso_count_lines(path, &bytes, &lines, &ignored) != MESO_OK)
        return MESO_OK; /* the reader reports an unreadable file in its own words */
    return meso_budget_check(meso_skeleton_estimate(bytes, lines), run->common.max_memory, MESO_LIMIT_ISSUE_SKELETON,
                             err, "skeleton %s (%llu bytes, up to %llu nodes)", path, (unsigned long long)bytes,
                             (unsigned long long)lines);
}

static meso_result load_skeleton(mesoi_bake_run* run, const char* path, double tolerance, meso_skeleton* sk,
                                 meso_bake_skeleton_info* src, meso_error* err)
{
    if (!path)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "no input skeleton given");
    if (!is_mesh_path(path)) {
        const meso_result r = check_skeleton_size(run, path, err);
        if (r != MESO_OK)
            return r;
    }
    if (mesoi_has_suffix(path, ".swc")) {
        src->input = "swc";
        return meso_skeleton_load(path, MESO_SKELETON_SWC, sk, err);
    }
    if (!is_mesh_path(path)) {
        src->input = "text";
        return meso_skeleton_load(path, MESO_SKELETON_TEXT, sk, err);
    }
    src->input = "mesh";
#if MESO_HAVE_CGAL
    meso_mesh m;
    meso_result r = mesoi_load_mesh(run, path, &m, &src->fixes, err);
    if (r != MESO_OK)
        return r;
    meso_skeleton_fit_options o = {.tolerance = tolerance};
    meso_skeleton_fit_stats st;
    r = meso_skeleton_from_mesh(&m, &o, sk, &st, err);
    if (r == MESO_OK) {
        /* Two-sided: the mesh's vertices to the frusta and sampled frusta
         * surface back to the mesh. */
        src->fit_error_max = st.hausdorff;
        src->fit_error_mean = st.fit_error_mean;
        src->mesh_to_frusta_max = st.fit_error_max;
        src->frusta_to_mesh_max = st.model_to_mesh_max;
        src->bbox_diagonal = st.bbox_diagonal;
        src->tolerance = st.tolerance;
        src->skeleton_nodes_extracted = st.cgal_nodes;
        src->mesh_triangles = st.mesh_triangles;
        mesoi_run_stage(run, "skeleton", 0.4, 0.4,
                        "skeleton: CGAL %u nodes (%.2f s), %u cycles cut, fitted %u nodes / %u segments; fit error "
                        "max %.4g (%.2f %% of the diagonal), mean %.4g",
                        st.cgal_nodes, st.seconds_cgal, st.cycles_broken, st.nodes, st.segments, st.hausdorff,
                        100 * st.hausdorff / st.bbox_diagonal, st.fit_error_mean);
    }
    meso_mesh_free(&m);
    return r;
#else
    (void)tolerance;
    return meso_bake_fail(err, MESO_ERR_UNSUPPORTED, 0,
                          "%s: skeletons from meshes need CGAL, which this build does not have", path);
#endif
}

meso_result meso_bake_skeleton_load(const char* path, double tolerance, const meso_bake_common* c,
                                    meso_bake_skeleton** out, meso_bake_skeleton_info* info, meso_error* err)
{
    *out = NULL;
    meso_bake_skeleton_info local;
    if (!info)
        info = &local;
    memset(info, 0, sizeof(*info));
    mesoi_bake_run run;
    mesoi_run_begin(&run, c);
    meso_bake_skeleton* s = calloc(1, sizeof(*s));
    if (!s || (path && !(s->path = strdup(path)))) {
        free(s);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    }
    meso_result r = load_skeleton(&run, path, tolerance, &s->sk, info, err);
    if (r != MESO_OK) {
        meso_bake_skeleton_free(s);
        return r;
    }
    info->node_count = s->sk.node_count;
    info->root_count = s->sk.root_count;
    s->info = *info;
    *out = s;
    return MESO_OK;
}

void meso_bake_skeleton_free(meso_bake_skeleton* s)
{
    if (!s)
        return;
    meso_skeleton_free(&s->sk);
    free(s->path);
    free(s);
}

static void report_json(cJSON* rep, const meso_bake_frusta_report* s)
{
    const meso_bake_skeleton_info* src = &s->skeleton;
    cJSON_AddNumberToObject(rep, "segments", s->segments);
    cJSON_AddNumberToObject(rep, "joints", s->joints);
    cJSON_AddNumberToObject(rep, "branch_points", s->branch_points);
    cJSON_AddNumberToObject(rep, "cap_intersections_found", s->cap_intersections_found);
    cJSON_AddNumberToObject(rep, "cap_intersections_unhandled", s->cap_intersections_unhandled);
    cJSON_AddNumberToObject(rep, "fit_error_max", s->fit_error_max);
    cJSON_AddNumberToObject(rep, "fit_error_mean", s->fit_error_mean);
    cJSON_AddStringToObject(rep, "input", src->input);
    cJSON_AddNumberToObject(rep, "tips", s->tips);
    cJSON_AddNumberToObject(rep, "balls", s->balls);
    cJSON_AddNumberToObject(rep, "ball_joints", s->ball_joints);
    cJSON_AddNumberToObject(rep, "sharp_joints", s->sharp_joints);
    cJSON_AddNumberToObject(rep, "unfitted_joints", s->unfitted_joints);
    cJSON_AddNumberToObject(rep, "degenerate_segments", s->degenerate_segments);
    cJSON_AddNumberToObject(rep, "seam_gap_max", s->seam_gap_max);
    cJSON_AddNumberToObject(rep, "seam_gap_mean", s->seam_gap_mean);
    cJSON_AddNumberToObject(rep, "radius_change_max", s->radius_change_max);
    if (s->level_count > 1) {
        cJSON* k = cJSON_AddObjectToObject(rep, "skeleton_levels");
        cJSON_AddNumberToObject(k, "count", s->skeleton_levels);
        if (s->skeleton_levels_stopped)
            cJSON_AddStringToObject(k, "stopped", s->skeleton_levels_stopped);
    }
    if (!strcmp(src->input, "mesh")) {
        cJSON_AddNumberToObject(rep, "tolerance", src->tolerance);
        cJSON_AddNumberToObject(rep, "bbox_diagonal", src->bbox_diagonal);
        cJSON_AddNumberToObject(rep, "mesh_to_frusta_max", src->mesh_to_frusta_max);
        cJSON_AddNumberToObject(rep, "frusta_to_mesh_max", src->frusta_to_mesh_max);
        cJSON_AddNumberToObject(rep, "mesh_triangles", src->mesh_triangles);
        cJSON_AddNumberToObject(rep, "skeleton_nodes_extracted", src->skeleton_nodes_extracted);
    }
    mesoi_report_fixes(rep, &src->fixes);
}

/* Native relief levels (bake/height_field_levels.h): the relief map
 * halved, drawn by the same frusta. A level's error is the exact sup of
 * its heights' change times the stand-in's relief gain (max over frusta of
 * depth x G_f, frusta_standin.h term 1: for a fixed (u, v) the surface
 * point is affine in the relief height, and |dp/dh| is at most that; the
 * walls between two frusta's reliefs are covered as there), with 4 float
 * ulps of slack in the heights; nothing else changes, so no chord or
 * rounding term. Levels stop before their error reaches the stand-in's,
 * and are kept while they are worth a place (mesoi_height_levels_trim:
 * what every level shares is the records and the colour). */
typedef struct native_levels {
    mesoi_height_level level[MESOI_HEIGHT_MAX_NATIVE];
    double error[MESOI_HEIGHT_MAX_NATIVE];
    uint32_t count;
} native_levels;

static meso_result relief_levels(const meso_bake_frusta_options* a, const meso_frusta_object* obj,
                                 const meso_texfn* relief, const meso_color_map* color, const meso_frusta_standin* st,
                                 native_levels* nl, meso_error* err)
{
    memset(nl, 0, sizeof *nl);
    const uint32_t want = mesoi_native_wanted(a->levels, MESOI_HEIGHT_MAX_NATIVE);
    if (!a->relief || relief->kind != MESO_TEXFN_HEIGHT || !(st->relief_gain > 0) || want == 0)
        return MESO_OK;
    uint32_t built = 0;
    const meso_result r = mesoi_height_levels_build(relief, NULL, want, st->error / st->relief_gain,
                                                    a->common.threads, nl->level, &built, err);
    if (r != MESO_OK)
        return r;
    const uint64_t shared = (uint64_t)obj->count * (MESO_FRUS_RECORD_SIZE + MESO_FSEG_RECORD_SIZE) +
                            (uint64_t)obj->ball_count * MESO_BALL_RECORD_SIZE +
                            (uint64_t)obj->node_count * MESO_SKEL_RECORD_SIZE +
                            (a->relief_color ? 4 * (uint64_t)color->width * color->height : 0);
    const uint32_t kept = mesoi_height_levels_trim(nl->level, built, shared, shared + relief->encoded_size);
    for (; nl->count < kept; ++nl->count) {
        const float e = mesoi_f32_up((nl->level[nl->count].sup + 4.0 * FLT_EPSILON) * st->relief_gain);
        if (!((double)e < st->error))
            break;
        nl->error[nl->count] = e;
    }
    mesoi_height_levels_free(nl->level + nl->count, kept - nl->count);
    return MESO_OK;
}

/* Frees encoded FRUS, FSEG and BALL payloads: level 0's and K coarser
 * skeletons'. */
static void free_records(uint8_t* frus, uint8_t* fseg, uint8_t* ball, uint8_t* coarse[][3], uint32_t K)
{
    free(frus);
    free(fseg);
    free(ball);
    for (uint32_t k = 0; k < K; ++k)
        for (int i = 0; i < 3; ++i)
            free(coarse[k][i]);
}

/* The file: META, RPRT, OBJT, SKEL, FRUS, FSEG, BALL (when there are balls),
 * RELF (with a relief), COLR (with a colour map); with levels, the relief
 * levels' RELF, the coarser skeletons' FRUS, FSEG and BALL, the stand-ins
 * and LODS. */
static meso_result assemble(const meso_bake_frusta_options* a, const meso_frusta_object* obj,
                            const meso_texfn* relief, const meso_color_map* color, const meso_frusta_standin* st,
                            const native_levels* nl, const mesoi_skeleton_level* sl, uint32_t K,
                            meso_bake_frusta_report* s, meso_bake_output** out, meso_error* err)
{
    uint8_t *frus = NULL, *fseg = NULL, *ball = NULL;
    uint8_t* coarse[MESOI_SKELETON_LEVELS_MAX][3] = {{NULL}};
    meso_result r = meso_frusta_object_encode(obj, &frus, &fseg, &ball, err);
    for (uint32_t k = 0; r == MESO_OK && k < K; ++k)
        r = meso_frusta_object_encode(&sl[k].obj, &coarse[k][0], &coarse[k][1], &coarse[k][2], err);
    if (r != MESO_OK) {
        free_records(frus, fseg, ball, coarse, K);
        return r;
    }
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_FRUSTA};
    memcpy(rec.bbox_min, obj->bbox_min, sizeof(rec.bbox_min));
    memcpy(rec.bbox_max, obj->bbox_max, sizeof(rec.bbox_max));
    snprintf(rec.name, sizeof(rec.name), "%s", mesoi_base_name(a->input));
    const meso_bake_skeleton_info* src = &s->skeleton;
    cJSON* meta = mesoi_meta_new("frusta");
    cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
    cJSON_AddStringToObject(params, "input", src->input);
    if (!strcmp(src->input, "mesh"))
        cJSON_AddNumberToObject(params, "tolerance", src->tolerance);
    cJSON_AddNumberToObject(params, "max_joint_angle", a->max_joint_angle);
    cJSON_AddBoolToObject(params, "minor_axis_fit", !a->no_fit);
    cJSON_AddBoolToObject(params, "keep_cap_intersections", a->keep_cap_intersections);
    if (a->twist != 0) /* absent when 0, so untwisted bakes keep their bytes */
        cJSON_AddNumberToObject(params, "twist", a->twist);
    if (a->relief) {
        cJSON* rl = cJSON_AddObjectToObject(params, "relief");
        cJSON_AddStringToObject(rl, "spec", a->relief);
        cJSON_AddNumberToObject(rl, "depth", s->relief_depth);
        cJSON_AddNumberToObject(rl, "repeat", a->relief_repeat);
    }
    if (a->relief_color) {
        cJSON* cl = cJSON_AddObjectToObject(params, "color");
        cJSON_AddStringToObject(cl, "file", mesoi_base_name(a->relief_color));
        cJSON_AddNumberToObject(cl, "repeat", a->relief_repeat);
    }
    cJSON* inputs = cJSON_AddArrayToObject(meta, "inputs");
    r = mesoi_add_input_provenance(inputs, a->input, err);
    if (r == MESO_OK && a->relief_color)
        r = mesoi_add_input_provenance(inputs, a->relief_color, err);
    meso_mesh_chunk mc = {0};
    mesoi_standin_levels lv = {0};
    if (r == MESO_OK && st) { /* level 1: the stand-in (frusta_standin.h), 2..: its simplifications */
        r = meso_bake_mesh_chunk(&st->mesh, NULL, &mc, err);
        if (r == MESO_OK)
            r = mesoi_standin_levels_build(&st->mesh, st->error,
                                           (a->levels && a->levels < MESOI_STANDIN_MAX_LEVELS ? a->levels
                                                                                         : MESOI_STANDIN_MAX_LEVELS) -
                                               (int)(nl->count + K),
                                           a->common.threads, &lv, err);
        /* The stand-ins' vertex colours (FORMAT.md §7.3 VCOL): with a
         * colour map, its colour and the relief's occlusion. Not for a
         * relief alone: its occlusion, which the stand-in would then show on
         * the draw's albedo, made the stand-in further from level 0, not
         * nearer (test_rt_standin_colour's saguaro: block error 13.0 with
         * it, 11.9 without), since the relief's scattered normals light it
         * more evenly than its occlusion darkens it. */
        meso_frusta_colours fc;
        mesoi_appearance shows;
        if (r == MESO_OK && a->relief_color) {
            meso_frusta_standin_appearance(obj, st, a->relief ? relief : NULL, color, &fc, &shows);
            r = mesoi_standin_levels_appearance(&lv, &st->mesh, 0.25 * meso_mesh_mean_edge(&st->mesh), &shows,
                                                a->common.threads, err);
        }
        lv.native = nl->count + K;
        for (uint32_t k = 0; k < nl->count; ++k)
            lv.native_error[k] = nl->error[k];
        /* A coarser skeleton draws the coarsest relief: its distance to
         * the full skeleton with that relief plus that relief's error
         * (the triangle inequality). */
        const double eN = nl->count ? nl->error[nl->count - 1] : 0;
        for (uint32_t k = 0; k < K; ++k) {
            const uint32_t i = nl->count + k;
            lv.native_error[i] = mesoi_f32_up(eN + sl[k].distance);
            lv.native_bbox[i] = 1;
            for (int c = 0; c < 3; ++c) {
                lv.native_min[i][c] = fminf(obj->bbox_min[c], sl[k].obj.bbox_min[c]);
                lv.native_max[i][c] = fmaxf(obj->bbox_max[c], sl[k].obj.bbox_max[c]);
            }
        }
        s->level_count = lv.count + 1 + nl->count + K;
        s->native_levels = nl->count;
        s->skeleton_levels = K;
        s->standin_triangles = st->mesh.triangle_count;
        s->standin_vertices = st->mesh.vertex_count;
        s->standin_bytes = mc.size;
        s->standin_error = st->error;
        s->standin_relief_error = st->relief_error;
        s->standin_chord_error = st->chord_error;
        cJSON_AddNumberToObject(params, "levels", a->levels); /* as mesh bakes: 0 auto; absent for 1 */
    }
    cJSON* rep = cJSON_CreateObject();
    report_json(rep, s);
    mesoi_chunk chunks[7 + MESOI_HEIGHT_MAX_NATIVE + 3 * MESOI_SKELETON_LEVELS_MAX +
                       2 * MESOI_STANDIN_MAX_LEVELS]; /* stand-ins: MESH and VCOL each */
    int count = 0;
    chunks[count++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_SKEL, .object = 1, .dims = {obj->node_count, 1, 1}},
                                    .data = obj->skel, .size = (size_t)obj->node_count * MESO_SKEL_RECORD_SIZE};
    chunks[count++] = (mesoi_chunk){
        .desc = {.type = MESO_CHUNK_FRUS, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1, .dims = {obj->count, 1, 1}},
        .data = frus, .size = (size_t)obj->count * MESO_FRUS_RECORD_SIZE};
    chunks[count++] = (mesoi_chunk){
        .desc = {.type = MESO_CHUNK_FSEG, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1, .dims = {obj->count, 1, 1}},
        .data = fseg, .size = (size_t)obj->count * MESO_FSEG_RECORD_SIZE};
    if (obj->ball_count)
        chunks[count++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_BALL, .flags = MESO_CHUNK_FLAG_REQUIRED,
                                                 .object = 1, .dims = {obj->ball_count, 1, 1}},
                                        .data = ball, .size = (size_t)obj->ball_count * MESO_BALL_RECORD_SIZE};
    if (a->relief)
        chunks[count++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_RELF, .object = 1, .dtype = relief->dtype,
                                                 .components = 1, .dims = {relief->dims[0], relief->dims[1], 1}},
                                        .data = relief->encoded, .size = relief->encoded_size};
    if (a->relief_color) /* sRGB RGBA8 as the PNG holds it, row 0 at the bottom (color_map.h) */
        chunks[count++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_COLR, .object = 1, .dtype = MESO_DTYPE_U8,
                                                 .components = 4, .dims = {color->width, color->height, 1}},
                                        .data = color->rgba, .size = 4 * (size_t)color->width * color->height};
    const uint32_t N = nl->count, T = N + K;
    if (r == MESO_OK && st && T) {
        /* Native relief levels 1..N: each its own RELF at lod l; then the
         * coarser skeletons N + 1..T: each its own FRUS, FSEG and BALL at
         * its lod, drawing level N's relief. What every level shares (SKEL,
         * the colour) is stored once at lod T, level 0's records at lod N,
         * and the coarsest relief at lod T, which levels N..T resolve it to
         * (FORMAT.md §7.10: a level takes each type at the smallest lod
         * >= its own). Without coarser skeletons (K = 0) this is the layout
         * of relief levels alone. */
        for (int k = 0; k < count; ++k) {
            const uint32_t type = chunks[k].desc.type;
            const int records = type == MESO_CHUNK_FRUS || type == MESO_CHUNK_FSEG || type == MESO_CHUNK_BALL;
            if (type != MESO_CHUNK_RELF || N == 0)
                chunks[k].desc.lod = (uint16_t)(records ? N : T);
        }
        for (uint32_t l = 1; l <= N; ++l) {
            const meso_texfn* t = &nl->level[l - 1].fn;
            chunks[count++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_RELF, .object = 1,
                                                     .lod = (uint16_t)(l == N ? T : l), .dtype = t->dtype,
                                                     .components = 1, .dims = {t->dims[0], t->dims[1], 1}},
                                            .data = t->encoded, .size = t->encoded_size};
        }
        for (uint32_t k = 0; k < K; ++k) {
            const meso_frusta_object* o = &sl[k].obj;
            const uint16_t lod = (uint16_t)(N + 1 + k);
            chunks[count++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_FRUS, .flags = MESO_CHUNK_FLAG_REQUIRED,
                                                     .object = 1, .lod = lod, .dims = {o->count, 1, 1}},
                                            .data = coarse[k][0], .size = (size_t)o->count * MESO_FRUS_RECORD_SIZE};
            chunks[count++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_FSEG, .flags = MESO_CHUNK_FLAG_REQUIRED,
                                                     .object = 1, .lod = lod, .dims = {o->count, 1, 1}},
                                            .data = coarse[k][1], .size = (size_t)o->count * MESO_FSEG_RECORD_SIZE};
            if (o->ball_count)
                chunks[count++] = (mesoi_chunk){
                    .desc = {.type = MESO_CHUNK_BALL, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1, .lod = lod,
                             .dims = {o->ball_count, 1, 1}},
                    .data = coarse[k][2], .size = (size_t)o->ball_count * MESO_BALL_RECORD_SIZE};
        }
    }
    if (r == MESO_OK && st) {
        /* The stand-in exists only as level N + 1 (the native levels do not
         * use it): append puts the tessellation's chunk there. */
        const mesoi_chunk tess = {.desc = {.type = MESO_CHUNK_MESH, .flags = MESO_CHUNK_FLAG_REQUIRED, .object = 1,
                                           .encoding = mc.encoding, .decoded_size = mc.decoded_size},
                                  .data = mc.data, .size = mc.size};
        count += (int)mesoi_standin_levels_append(&lv, &st->mesh, &tess, rec.bbox_min, rec.bbox_max, chunks + count,
                                                  rep);
        cJSON* l1 = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(rep, "levels"), 1 + (int)nl->count);
        cJSON_AddNumberToObject(l1, "vertices", s->standin_vertices);
        cJSON_AddNumberToObject(l1, "relief_error", s->standin_relief_error);
        cJSON_AddNumberToObject(l1, "chord_error", s->standin_chord_error);
        cJSON_AddNumberToObject(l1, "cells_around_min", st->nu_min);
        cJSON_AddNumberToObject(l1, "cells_around_max", st->nu_max);
        /* A native level draws no MESH: its relief or its frusta instead. */
        for (uint32_t l = 1; l <= T; ++l) {
            cJSON* o = cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(rep, "levels"), (int)l);
            cJSON_DeleteItemFromObjectCaseSensitive(o, "triangles");
            cJSON_DeleteItemFromObjectCaseSensitive(o, "mesh_bytes");
            const meso_texfn* t = l <= N ? &nl->level[l - 1].fn : N ? &nl->level[N - 1].fn : a->relief ? relief : NULL;
            if (t) {
                cJSON_AddNumberToObject(o, "relief_width", t->dims[0]);
                cJSON_AddNumberToObject(o, "relief_height", t->dims[1]);
            }
            if (l <= N) {
                cJSON_AddNumberToObject(o, "relief_bytes", (double)t->encoded_size);
                continue;
            }
            const mesoi_skeleton_level* k = &sl[l - N - 1];
            cJSON_AddNumberToObject(o, "frusta", k->obj.count);
            cJSON_AddNumberToObject(o, "balls", k->obj.ball_count);
            cJSON_AddNumberToObject(o, "skeleton_nodes", k->nodes);
            cJSON_AddNumberToObject(o, "skeleton_distance", k->distance);
            cJSON_AddNumberToObject(o, "records_bytes",
                                    (double)k->obj.count * (MESO_FRUS_RECORD_SIZE + MESO_FSEG_RECORD_SIZE) +
                                        (double)k->obj.ball_count * MESO_BALL_RECORD_SIZE);
        }
    }
    if (r == MESO_OK)
        r = mesoi_output_build(meta, rep, &rec, chunks, count, out, err);
    free(mc.data);
    mesoi_standin_levels_free(&lv);
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    free_records(frus, fseg, ball, coarse, K);
    return r;
}

/* A rate times a long segment can exceed what a float u resolves: refuse a
 * segment over MESO_SKEL_MAX_TWIST_DEG (a .skel twist= beyond it never
 * parses). */
static meso_result check_twists(const meso_skeleton* sk, const meso_frustum_model* m, double rate, meso_error* err)
{
    for (uint32_t i = 0; i < m->segment_count; ++i) {
        const meso_frustum_segment* s = &m->segments[i];
        const double deg = fabs(s->twist) * (180 / M_PI);
        const uint32_t line = sk->nodes[s->node[1]].line;
        if (deg > MESO_SKEL_MAX_TWIST_DEG)
            return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                                  "--twist %g degrees per unit length twists the segment ending at %s %u by %.6g "
                                  "degrees, more than %g (1000 turns): use a smaller rate",
                                  rate, line ? "line" : "node", line ? line : s->node[1] + 1, deg,
                                  MESO_SKEL_MAX_TWIST_DEG);
    }
    return MESO_OK;
}

static void fill_report(const meso_frustum_model* m, const meso_frusta_object* obj, meso_bake_frusta_report* s)
{
    const meso_frustum_stats* st = &m->stats;
    s->segments = st->segments;
    s->joints = st->joints;
    s->branch_points = st->branch_points;
    s->tips = st->tips;
    s->balls = obj->ball_count;
    s->ball_joints = st->ball_joints;
    s->sharp_joints = st->sharp_joints;
    s->unfitted_joints = st->unfitted_joints;
    s->degenerate_segments = st->degenerate_segments;
    s->cap_intersections_found = st->cap_intersections_found;
    s->cap_intersections_unhandled = st->cap_intersections_unhandled;
    s->seam_gap_max = st->seam_gap_max;
    s->seam_gap_mean = st->seam_gap_mean;
    s->radius_change_max = st->radius_change_max;
    /* fit_error for skeleton input: how far the §2.2 fit moved the cone
     * radii at the nodes from the input's. */
    const int mesh_in = !strcmp(s->skeleton.input, "mesh");
    s->fit_error_max = mesh_in ? s->skeleton.fit_error_max : st->radius_change_max;
    s->fit_error_mean = mesh_in ? s->skeleton.fit_error_mean : st->radius_change_mean;
}

meso_result meso_bake_frusta(const meso_bake_frusta_options* o, meso_bake_output** out,
                             meso_bake_frusta_report* report, meso_error* err)
{
    if (!o || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "meso_bake_frusta: NULL options or output");
    *out = NULL;
    meso_bake_frusta_options a = *o;
    if (!a.relief_repeat)
        a.relief_repeat = 1;
    if (!(a.max_joint_angle >= 0 && a.max_joint_angle <= 180) || !(a.relief_repeat > 0 && a.relief_repeat <= 1e4) ||
        !(a.relief_depth >= 0) || !(a.tolerance >= 0) || !(fabs(a.twist) <= MESO_BAKE_MAX_TWIST) ||
        a.levels < 0 || a.levels > (int)MESO_BAKE_FRUSTA_MAX_LEVELS)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                              "frusta options: max_joint_angle in [0, 180], relief_repeat in (0, 10000], "
                              "relief_depth and tolerance >= 0, |twist| <= %g degrees per unit length, levels "
                              "0 (auto) or 1..%u",
                              MESO_BAKE_MAX_TWIST, MESO_BAKE_FRUSTA_MAX_LEVELS);
    if (a.relief_depth > 0 && !a.relief)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "frusta options: relief_depth needs a relief");
    meso_bake_frusta_report rep_local;
    meso_bake_frusta_report* s = report ? report : &rep_local;
    memset(s, 0, sizeof(*s));
    mesoi_bake_run run;
    mesoi_run_begin(&run, &a.common);
    meso_skeleton sk = {0};
    meso_frustum_model m = {0};
    meso_frusta_object obj = {0};
    meso_texfn relief = {0};
    meso_color_map color = {0};

    /* A skeleton loaded before (meso_bake_skeleton_load) is used as it is. */
    const meso_skeleton* skel = &sk;
    meso_result r = MESO_OK;
    if (a.skeleton && a.input)
        r = meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "both an input path and a loaded skeleton given");
    else if (a.skeleton) {
        skel = &a.skeleton->sk;
        s->skeleton = a.skeleton->info;
        a.input = a.skeleton->path;
    } else {
        r = load_skeleton(&run, a.input, a.tolerance, &sk, &s->skeleton, err);
    }
    s->skeleton.node_count = skel->node_count;
    s->skeleton.root_count = skel->root_count;
    if (r == MESO_OK && strcmp(s->skeleton.input, "mesh") != 0) /* nothing to draw is an invalid input, not a bake */
        r = meso_skeleton_require_drawable(skel, err);
    if (r == MESO_OK)
        mesoi_run_stage(&run, "skeleton", 0.5, 0.5, "%s: %u nodes, %u roots (%s input)", a.input, skel->node_count,
                        skel->root_count, s->skeleton.input);
    if (r == MESO_OK && a.relief) {
        r = meso_texfn_from_spec_max(a.relief, run.common.max_memory, &relief, err);
        if (r == MESO_OK && relief.kind != MESO_TEXFN_HEIGHT)
            r = meso_bake_fail(err, MESO_ERR_INVALID_ARG, MESO_TEXFN_ISSUE_SPEC,
                               "--relief '%s' is a volume; frusta take height fields (height:FILE.png, bricks, "
                               "cobble, ribs)",
                               a.relief);
    }
    if (r == MESO_OK && a.relief_color)
        r = meso_color_map_load_png(a.relief_color, run.common.max_memory, &color, err);
    const meso_frustum_options fo = {.keep_cap_intersections = a.keep_cap_intersections,
                                     .no_minor_axis_fit = a.no_fit, .max_joint_angle_deg = a.max_joint_angle,
                                     .twist_per_length = a.twist * (M_PI / 180)};
    if (r == MESO_OK)
        r = meso_frustum_model_build(skel, &fo, &m, err);
    if (r == MESO_OK)
        r = check_twists(skel, &m, a.twist, err);
    if (r == MESO_OK)
        mesoi_run_stage(&run, "frusta", 0.8, 0.8,
                        "%u frusta, %u joints (%u ball joints: %u sharp, %u unfitted, cap intersections %u found, %u "
                        "unhandled), %u branch points, seam gap max %.3g",
                        m.stats.segments, m.stats.joints, m.stats.ball_joints, m.stats.sharp_joints,
                        m.stats.unfitted_joints, m.stats.cap_intersections_found,
                        m.stats.cap_intersections_unhandled, m.stats.branch_points, m.stats.seam_gap_max);
    double depth = 0;
    if (r == MESO_OK && a.relief) {
        depth = a.relief_depth;
        if (depth <= 0) {
            double sum = 0;
            for (uint32_t i = 0; i < m.segment_count; ++i)
                sum += 0.5 * (m.segments[i].r0 + m.segments[i].r1);
            depth = 0.25 * sum / m.segment_count;
        }
        if (!(depth > 0))
            r = meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                               "--relief needs --relief-depth: every radius is 0, so no default depth");
    }
    s->relief_depth = depth;
    const meso_frusta_relief_params rp = {.depth = depth, .u_repeat = a.relief_repeat};
    if (r == MESO_OK)
        r = meso_frusta_object_build(skel, &m, &rp, &obj, err);
    meso_frusta_standin st = {0};
    int with_standin = 0;
    s->level_count = 1;
    if (r == MESO_OK && a.levels != 1) {
        const double t = meso_seconds();
        meso_error serr = {0};
        const meso_result sr = meso_frusta_standin_build(&obj, a.relief ? &relief : NULL, &st, &serr);
        if (sr == MESO_OK) {
            with_standin = 1;
            mesoi_run_stage(&run, "levels", 0.9, 0.9,
                            "level 1: %u triangles (%u..%u cells around), error %.4g (relief %.4g, chord %.4g) "
                            "(%.0f ms)",
                            st.mesh.triangle_count, st.nu_min, st.nu_max, st.error, st.relief_error,
                            st.chord_error, 1e3 * (meso_seconds() - t));
        } else if (sr == MESO_ERR_UNSUPPORTED)
            mesoi_run_stage(&run, "levels", 0.9, 0.9, "one level: %s", serr.message);
        else {
            r = sr;
            if (err)
                *err = serr;
        }
    }
    native_levels nl = {0};
    if (r == MESO_OK && with_standin) {
        const double t = meso_seconds();
        r = relief_levels(&a, &obj, &relief, &color, &st, &nl, err);
        if (r == MESO_OK && nl.count)
            mesoi_run_stage(&run, "levels", 0.92, 0.92,
                            "%u native relief levels, down to %ux%u, error %.4g (%.0f ms)", nl.count,
                            nl.level[nl.count - 1].fn.dims[0], nl.level[nl.count - 1].fn.dims[1],
                            nl.error[nl.count - 1], 1e3 * (meso_seconds() - t));
    }
    mesoi_skeleton_level* sl = NULL;
    uint32_t K = 0;
    if (r == MESO_OK && with_standin) {
        const double t = meso_seconds();
        const uint32_t room = mesoi_native_wanted(a.levels, MESOI_STANDIN_MAX_LEVELS - 2);
        const meso_texfn* drawn = nl.count ? &nl.level[nl.count - 1].fn : a.relief ? &relief : NULL;
        mesoi_skeleton_levels_input in = {
            .sk = skel, .fo = &fo, .rp = &rp, .fine = &obj, .free_u = !a.relief && !a.relief_color,
            .max_levels = room > nl.count ? (room - nl.count < MESOI_SKELETON_LEVELS_MAX ? room - nl.count
                                                                                       : MESOI_SKELETON_LEVELS_MAX)
                                          : 0,
            .limit = st.error - (nl.count ? nl.error[nl.count - 1] : 0)};
        if (drawn)
            meso_frusta_height_range(drawn, &in.h_lo, &in.h_hi);
        r = mesoi_skeleton_levels_build(&in, &sl, &K, &s->skeleton_levels_stopped, err);
        if (r == MESO_OK && K)
            mesoi_run_stage(&run, "levels", 0.94, 0.94,
                            "%u coarser skeletons, down to %u frusta (of %u), distance %.4g%s%s (%.0f ms)", K,
                            sl[K - 1].obj.count, obj.count, sl[K - 1].distance,
                            s->skeleton_levels_stopped ? "; stopped: " : "",
                            s->skeleton_levels_stopped ? s->skeleton_levels_stopped : "", 1e3 * (meso_seconds() - t));
        else if (r == MESO_OK)
            mesoi_run_stage(&run, "levels", 0.94, 0.94, "no coarser skeleton: %s (%.0f ms)",
                            s->skeleton_levels_stopped ? s->skeleton_levels_stopped : "no room for one",
                            1e3 * (meso_seconds() - t));
    }
    if (r == MESO_OK) {
        fill_report(&m, &obj, s);
        r = assemble(&a, &obj, &relief, &color, with_standin ? &st : NULL, &nl, sl, K, s, out, err);
    }
    mesoi_skeleton_levels_free(sl, K);
    mesoi_height_levels_free(nl.level, nl.count);
    meso_frusta_standin_free(&st);
    meso_texfn_free(&relief);
    meso_color_map_free(&color);
    meso_frusta_object_free(&obj);
    meso_frustum_model_free(&m);
    meso_skeleton_free(&sk);
    if (r == MESO_OK)
        mesoi_run_done(&run);
    return r;
}
