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
#include "meso_layout.h"
#include "mesh_levels.h"
#include "mesh_parts.h"

meso_bake_mesh_options meso_bake_mesh_defaults(void)
{
    return (meso_bake_mesh_options){0};
}

static void st32(uint8_t* p, uint32_t v)
{
    for (int k = 0; k < 4; ++k)
        p[k] = (uint8_t)(v >> (8 * k));
}

/* The parts (FORMAT.md §7.11, mesh_parts.c): one PMSH per part and level
 * (dims[0] the part number, lod the part's level), and the PRTS chunk: a
 * record per part level (LODS layout, `object` the part number; errors
 * rounded up to f32) and the neighbour pairs. Nothing when the mesh is too
 * small to cut. */
static meso_result write_parts(mesoi_bake_run* run, const meso_mesh* m, const meso_bake_mesh_options* o,
                               const meso_draco_options* dopt, meso_writer* w, meso_bake_mesh_report* rp,
                               cJSON** jout, meso_error* err)
{
    meso_mesh_parts P;
    const meso_mesh_parts_options po = {.part_triangles = o->parts > 0 ? (uint32_t)o->parts : 0,
                                        .max_levels = o->levels,
                                        .threads = o->common.threads};
    meso_result r = meso_mesh_parts_build(m, &po, &P, err);
    uint32_t records = 0;
    for (uint32_t p = 0; r == MESO_OK && p < P.count; ++p)
        records += P.part[p].level_count;
    const size_t size = MESO_PRTS_HDR_SIZE + (size_t)records * MESO_LODS_RECORD_SIZE +
                        (size_t)P.edge_count * MESO_PRTS_EDGE_SIZE;
    uint8_t* prts = r == MESO_OK && P.count ? calloc(1, size) : NULL;
    if (r == MESO_OK && P.count && !prts)
        r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "mesh parts: out of memory");
    size_t bytes = 0;
    uint32_t k = 0;
    for (uint32_t p = 0; r == MESO_OK && p < P.count; ++p)
        for (uint32_t l = 0; r == MESO_OK && l < P.part[p].level_count; ++l) {
            const meso_mesh_part_level* L = &P.part[p].level[l];
            meso_mesh_chunk chunk;
            if ((r = meso_bake_mesh_chunk(&L->mesh, dopt, &chunk, err)) != MESO_OK)
                break;
            const meso_chunk_desc d = {.type = MESO_CHUNK_PMSH,
                                       .object = 1,
                                       .lod = (uint16_t)l,
                                       .encoding = chunk.encoding,
                                       .decoded_size = chunk.decoded_size,
                                       .dims = {p + 1, 1, 1}};
            r = meso_writer_add(w, &d, chunk.data, chunk.size, err);
            free(chunk.data);
            bytes += chunk.size;
            meso_level_record lr = {.object = p + 1, .lod = (uint16_t)l, .form = MESO_LEVEL_NATIVE};
            float e = (float)L->error;
            if ((double)e < L->error)
                e = nextafterf(e, INFINITY);
            lr.error = e;
            for (int a = 0; a < 3; ++a) {
                lr.bbox_min[a] = (float)L->bbox_min[a];
                lr.bbox_max[a] = (float)L->bbox_max[a];
            }
            meso_level_record_encode(&lr, prts + MESO_PRTS_HDR_SIZE + (size_t)k++ * MESO_LODS_RECORD_SIZE);
        }
    if (r == MESO_OK && P.count) {
        st32(prts + MESO_PRTS_OFF_PARTS, P.count);
        st32(prts + MESO_PRTS_OFF_RECORDS, records);
        st32(prts + MESO_PRTS_OFF_EDGES, P.edge_count);
        uint8_t* e = prts + MESO_PRTS_HDR_SIZE + (size_t)records * MESO_LODS_RECORD_SIZE;
        for (uint32_t i = 0; i < 2 * P.edge_count; ++i)
            st32(e + 4 * (size_t)i, P.edges[i] + 1); /* part numbers */
        const meso_chunk_desc d = {.type = MESO_CHUNK_PRTS, .object = 1};
        r = meso_writer_add(w, &d, prts, size, err);
        bytes += size;
        rp->parts = P.count;
        rp->part_levels = records;
        rp->part_bytes = bytes;
        cJSON* j = cJSON_CreateObject();
        cJSON_AddNumberToObject(j, "count", P.count);
        cJSON_AddNumberToObject(j, "levels", records);
        cJSON_AddNumberToObject(j, "neighbour_pairs", P.edge_count);
        cJSON_AddNumberToObject(j, "bytes", (double)bytes);
        *jout = j;
        mesoi_run_stage(run, "parts", 0.9, 0.95, "%u parts, %u part levels, %zu bytes (%.0f ms)", P.count, records,
                        bytes, mesoi_run_ms(run));
    }
    free(prts);
    meso_mesh_parts_free(&P);
    return r;
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
    if (o->parts < -1 || (o->parts > 0 && o->parts < 64)) { /* before the levels' work */
        meso_mesh_free(&m);
        return meso_bake_fail(err, MESO_ERR_INVALID_ARG, 0, "parts of %d triangles: at least 64 (or 0 = auto, -1 = none)",
                              o->parts);
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
    cJSON* jparts = NULL;
    if (r == MESO_OK && nlv > 0 && o->parts >= 0)
        r = write_parts(&run, &m, o, o->draco ? &dopt : NULL, w, rp, &jparts, err);
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
    if (jparts)
        cJSON_AddItemToObject(rep, "parts", jparts);

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
