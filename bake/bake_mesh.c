/* bake_mesh.c — meso_bake_mesh (`mesobake mesh`): a mesh as one MESH object,
 * raw or Draco-compressed (FORMAT.md §7.1). */
#include "bake_internal.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "mesh_chunk.h"

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
    if (o->draco && (dopt.position_bits < 1 || dopt.position_bits > 30 || dopt.normal_bits < 2 ||
                     dopt.normal_bits > 30 || dopt.uv_bits < 1 || dopt.uv_bits > 30))
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0,
                              "Draco bits %d,%d,%d: positions and uvs need 1..30, normals 2..30", dopt.position_bits,
                              dopt.normal_bits, dopt.uv_bits);
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

    meso_mesh_chunk chunk;
    r = meso_bake_mesh_chunk(&m, o->draco ? &dopt : NULL, &chunk, err);
    if (r != MESO_OK) {
        meso_mesh_free(&m);
        return r;
    }
    double lo[3], hi[3];
    const double diag = meso_mesh_bounds(&m, lo, hi);
    rp->bbox_diagonal = diag;
    rp->mesh_bytes = chunk.size;
    meso_object_record rec = {.id = 1, .kind = MESO_OBJECT_MESH};
    for (int k = 0; k < 3; ++k) {
        rec.bbox_min[k] = (float)lo[k];
        rec.bbox_max[k] = (float)hi[k];
    }
    snprintf(rec.name, sizeof(rec.name), "%s", o->name ? o->name : mesoi_input_label(o->input));

    cJSON* meta = mesoi_meta_new("mesh");
    cJSON* params = cJSON_AddObjectToObject(meta, "parameters");
    cJSON_AddStringToObject(params, "encoding", o->draco ? "draco" : "raw");
    if (o->draco) {
        cJSON_AddNumberToObject(params, "draco_position_bits", dopt.position_bits);
        cJSON_AddNumberToObject(params, "draco_normal_bits", dopt.normal_bits);
        cJSON_AddNumberToObject(params, "draco_uv_bits", dopt.uv_bits);
    }
    r = mesoi_add_provenance(cJSON_AddArrayToObject(meta, "inputs"), o->input, o->mesh, err);

    cJSON* rep = cJSON_CreateObject();
    mesoi_report_fixes(rep, &rp->fixes);
    cJSON_AddNumberToObject(rep, "vertices", m.vertex_count);
    cJSON_AddNumberToObject(rep, "triangles", m.triangle_count);
    cJSON_AddNumberToObject(rep, "bbox_diagonal", diag);
    cJSON_AddStringToObject(rep, "encoding", o->draco ? "draco" : "raw");
    cJSON_AddNumberToObject(rep, "mesh_bytes", (double)chunk.size);

    const mesoi_chunk chunks[1] = {{.desc = {.type = MESO_CHUNK_MESH,
                                             .flags = MESO_CHUNK_FLAG_REQUIRED,
                                             .object = 1,
                                             .encoding = chunk.encoding,
                                             .decoded_size = chunk.decoded_size},
                                    .data = chunk.data,
                                    .size = chunk.size}};
    if (r == MESO_OK)
        r = mesoi_output_build(meta, rep, &rec, chunks, 1, out, err);
    free(chunk.data);
    cJSON_Delete(meta);
    cJSON_Delete(rep);
    meso_mesh_free(&m);
    if (r == MESO_OK)
        mesoi_run_done(&run);
    return r;
}
