/* bake_mesh.c — meso_bake_mesh (`mesobake mesh`): a mesh as one MESH object,
 * raw or Draco-compressed (FORMAT.md §7.3), with its levels of detail: one
 * MESH per level (lod L) and their LODS records (§7.10, mesh_levels.c). */
#include "bake_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "lod_table.h"
#include "mesh_chunk.h"
#include "mesh_levels.h"

meso_bake_mesh_options meso_bake_mesh_defaults(void)
{
    return (meso_bake_mesh_options){0};
}

meso_result meso_bake_mesh(const meso_bake_mesh_options* o, meso_bake_output** out, meso_bake_mesh_report* report,
                           meso_error* err)
{
    if (!o || !out)
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "meso_bake_mesh: NULL options or output");
    *out = NULL;
    meso_bake_mesh_report rep_local;
    meso_bake_mesh_report* rp = report ? report : &rep_local;
    memset(rp, 0, sizeof(*rp));
    const meso_draco_options dopt = {o->draco_position_bits ? o->draco_position_bits : 14,
                                     o->draco_normal_bits ? o->draco_normal_bits : 10,
                                     o->draco_uv_bits ? o->draco_uv_bits : 12, 7};
    if (o->draco && (dopt.position_bits < 1 || dopt.position_bits > MESO_DRACO_MAX_BITS || dopt.normal_bits < 2 ||
                     dopt.normal_bits > MESO_DRACO_MAX_BITS || dopt.uv_bits < 1 ||
                     dopt.uv_bits > MESO_DRACO_MAX_BITS))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "Draco bits %d,%d,%d: positions and uvs need 1..%d, normals 2..%d",
                              dopt.position_bits, dopt.normal_bits, dopt.uv_bits, MESO_DRACO_MAX_BITS,
                              MESO_DRACO_MAX_BITS);
    mesoi_bake_run run;
    mesoi_run_begin(&run, &o->common);
    meso_mesh m;
    meso_result r = mesoi_load_input(&run, o->input, o->mesh, &m, &rp->fixes, err);
    if (r != MESO_OK)
        return r;
    rp->vertices = m.vertex_count;
    rp->triangles = m.triangle_count;
    rp->has_normals = m.normals != NULL;
    rp->has_uvs = m.uvs != NULL;
    rp->draco = o->draco != 0;
    mesoi_run_stage(&run, "load", 0.5, 0.5, "read %s: %u vertices, %u triangles%s%s (%.0f ms)",
                    mesoi_input_label(o->input), m.vertex_count, m.triangle_count, m.normals ? ", normals" : "",
                    m.uvs ? ", uvs" : "", mesoi_run_ms(&run));

    /* Levels of detail: the coarse meshes and their measured errors. */
    const int want = o->levels;
    if (want < 0 || want > MESO_BAKE_MESH_MAX_LEVELS) {
        meso_mesh_free(&m);
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "levels %d: 0 (auto) or 1..%d", want,
                              MESO_BAKE_MESH_MAX_LEVELS);
    }
    meso_mesh_level* lv = NULL;
    uint32_t nlv = 0;
#if !MESO_HAVE_MESHOPTIMIZER
    if (want == 0)
        mesoi_run_warning(&run, 0, "built without meshoptimizer: one level of detail");
    else
#endif
    {
        const meso_mesh_levels_options lo = {.max_levels = want, .threads = o->common.threads};
        r = meso_mesh_levels_build(&m, &lo, &lv, &nlv, err);
        if (r != MESO_OK) {
            meso_mesh_free(&m);
            return r;
        }
    }
    mesoi_run_stage(&run, "levels", 0.8, 0.9, "%u levels of detail (%.0f ms)", nlv + 1, mesoi_run_ms(&run));

    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(&m, lo, hi);
    rp->bbox_diagonal = diag;
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_MESH};
    for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = (float)lo[k];
        rec.bbox_max[k] = (float)hi[k];
    }
    snprintf(rec.name, sizeof(rec.name), "%s", o->name ? o->name : mesoi_input_label(o->input));

    /* One MESH chunk per level (lod L), and their LODS records. */
    meso_writer* w = NULL;
    mesoi_lod_table lods = {0};
    cJSON* jlevels = cJSON_CreateArray();
    r = meso_writer_create(NULL, &w);
    for (uint32_t L = 0; r == MESO_OK && L <= nlv; ++L) {
        const meso_mesh* lm = L == 0 ? &m : &lv[L - 1].mesh;
        meso_mesh_chunk chunk;
        r = meso_bake_mesh_chunk(lm, o->draco ? &dopt : NULL, &chunk, err);
        if (r != MESO_OK)
            break;
        const meso_chunk_desc d = {.type = MESO_CHUNK_MESH,
                                   .flags = MESO_CHUNK_FLAG_REQUIRED,
                                   .object = 1,
                                   .lod = (uint16_t)L,
                                   .encoding = chunk.encoding,
                                   .decoded_size = chunk.decoded_size};
        r = meso_writer_add(w, &d, chunk.data, chunk.size, err);
        free(chunk.data);
        meso_level_record lr = {.object = 1, .lod = (uint16_t)L, .form = MESO_LEVEL_NATIVE};
        meso_bake_mesh_level* rl = &rp->level[L];
        rl->vertices = lm->vertex_count;
        rl->triangles = lm->triangle_count;
        rl->mesh_bytes = chunk.size;
        for (int k = 0; k < 3; ++k) {
            lr.bbox_min[k] = L == 0 ? rec.bbox_min[k] : (float)lv[L - 1].bbox_min[k];
            lr.bbox_max[k] = L == 0 ? rec.bbox_max[k] : (float)lv[L - 1].bbox_max[k];
        }
        if (L > 0) {
            /* Rounded up to f32, so the stored bound is still a bound. */
            float e = (float)lv[L - 1].error;
            if ((double)e < lv[L - 1].error)
                e = nextafterf(e, INFINITY);
            lr.error = e;
            rl->error = lv[L - 1].error;
            rl->sample_radius = lv[L - 1].sample_radius;
        }
        if (r == MESO_OK)
            r = mesoi_lod_table_add(&lods, &lr, err);
        cJSON* jl = cJSON_CreateObject();
        cJSON_AddNumberToObject(jl, "lod", L);
        cJSON_AddNumberToObject(jl, "vertices", lm->vertex_count);
        cJSON_AddNumberToObject(jl, "triangles", lm->triangle_count);
        cJSON_AddNumberToObject(jl, "error", lr.error);
        cJSON_AddNumberToObject(jl, "sample_radius", rl->sample_radius);
        cJSON_AddNumberToObject(jl, "mesh_bytes", (double)chunk.size);
        cJSON_AddItemToArray(jlevels, jl);
    }
    rp->level_count = nlv + 1;
    rp->mesh_bytes = rp->level[0].mesh_bytes;
    if (r == MESO_OK)
        r = mesoi_lod_table_write(&lods, w, err);
    mesoi_lod_table_free(&lods);
    meso_mesh_levels_free(lv, nlv);

    cJSON* meta = mesoi_meta_new("mesh");
    cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
    cJSON_AddStringToObject(params, "encoding", o->draco ? "draco" : "raw");
    if (o->draco) {
        cJSON_AddNumberToObject(params, "draco_position_bits", dopt.position_bits);
        cJSON_AddNumberToObject(params, "draco_normal_bits", dopt.normal_bits);
        cJSON_AddNumberToObject(params, "draco_uv_bits", dopt.uv_bits);
    }
    if (want != 1) /* --levels 1 keeps the META of earlier versions */
        cJSON_AddNumberToObject(params, "levels", want);
    if (r == MESO_OK)
        r = mesoi_add_provenance(cJSON_AddArrayToObject(meta, "inputs"), o->input, o->mesh, err);

    cJSON* rep = cJSON_CreateObject();
    mesoi_report_fixes(rep, &rp->fixes);
    cJSON_AddNumberToObject(rep, "vertices", m.vertex_count);
    cJSON_AddNumberToObject(rep, "triangles", m.triangle_count);
    cJSON_AddNumberToObject(rep, "bbox_diagonal", diag);
    cJSON_AddStringToObject(rep, "encoding", o->draco ? "draco" : "raw");
    cJSON_AddNumberToObject(rep, "mesh_bytes", (double)rp->mesh_bytes);
    if (nlv > 0)
        cJSON_AddItemToObject(rep, "levels", jlevels);
    else
        cJSON_Delete(jlevels);

    if (r == MESO_OK)
        r = mesoi_output_finish(meta, rep, &rec, 1, &w, out, err);
    meso_writer_destroy(w);
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    meso_mesh_free(&m);
    if (r == MESO_OK)
        mesoi_run_done(&run);
    return r;
}
