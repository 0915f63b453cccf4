/*
 * standin_levels.c — see standin_levels.h.
 */
#include "standin_levels.h"

#include "surface_distance.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

meso_result mesoi_standin_levels_build(const meso_mesh* base, double e0, int levels, int threads,
                                       mesoi_standin_levels* out, meso_error* err)
{
    memset(out, 0, sizeof *out);
    out->e0 = e0;
    out->count = 1;
    if (levels == 2 || !MESO_HAVE_MESHOPTIMIZER)
        return MESO_OK;
    if (levels > MESOI_STANDIN_MAX_LEVELS)
        levels = MESOI_STANDIN_MAX_LEVELS;
    /* The samples of the simplifications' errors: half the mean edge (as
     * mesobake mesh) or a quarter of e0, the larger. Every stand-in's
     * error is e0 + its own, so a sampling radius up to e0 / (4 sqrt 3)
     * loosens it by at most 14 % of e0, and on a shell (e0 = its thickness
     * times the highest texel, often ten mean edges) it takes the chain's
     * measurement from the bulk of the bake to a small part of it. The
     * shell bake passes the e0 its directors may reach (bake_shell.c,
     * standin_e0_sampling) and stores the e0 they reached, which is less
     * where repair shortened every longest director: there the radius may
     * be a larger share of the stored e0 (a looser bound, still a bound). */
    const double spacing = fmax(0.5 * meso_mesh_mean_edge(base), 0.25 * e0);
    const meso_mesh_levels_options lo = {.max_levels = levels ? levels - 1 : MESOI_STANDIN_MAX_LEVELS - 1,
                                         .threads = threads, .spacing = spacing};
    meso_result r = meso_mesh_levels_build(base, &lo, &out->chain, &out->chain_count, err);
    for (uint32_t k = 0; r == MESO_OK && k < out->chain_count; ++k)
        r = meso_bake_mesh_chunk(&out->chain[k].mesh, NULL, &out->chunk[k], err);
    if (r != MESO_OK) {
        mesoi_standin_levels_free(out);
        return r;
    }
    out->count += out->chain_count;
    return MESO_OK;
}

size_t mesoi_standin_levels_append(mesoi_standin_levels* lv, const meso_mesh* base, const mesoi_chunk* base_chunk,
                                   const float l0_min[3], const float l0_max[3], mesoi_chunk* chunks, cJSON* rep)
{
    size_t n = 0;
    const uint32_t N = lv->native, total = 1 + N + lv->count;
    cJSON* jl = cJSON_AddArrayToObject(rep, "levels");
    for (uint32_t L = 0; L < total; ++L) {
        const int native = L <= N;
        const uint32_t S = L - N; /* stand-in number: 1 the base mesh, 2.. the chain */
        meso_level_record lr = {.object = base_chunk->desc.object, .lod = (uint16_t)L,
                                .form = native ? MESO_LEVEL_NATIVE : MESO_LEVEL_MESH};
        const meso_mesh* lm = native || S == 1 ? base : &lv->chain[S - 2].mesh;
        size_t bytes = base_chunk->size;
        double e = 0;
        if (native) {
            memcpy(lr.bbox_min, l0_min, sizeof lr.bbox_min);
            memcpy(lr.bbox_max, l0_max, sizeof lr.bbox_max);
            e = L ? lv->native_error[L - 1] : 0;
        } else if (S == 1) {
            double lo[3], hi[3];
            meso_mesh_bounds(base, lo, hi);
            for (int k = 0; k < 3; ++k) {
                lr.bbox_min[k] = (float)lo[k];
                lr.bbox_max[k] = (float)hi[k];
            }
            e = lv->e0;
            chunks[n] = *base_chunk;
            chunks[n++].desc.lod = (uint16_t)L;
        } else {
            const meso_mesh_level* c = &lv->chain[S - 2];
            const meso_mesh_chunk* mc = &lv->chunk[S - 2];
            for (int k = 0; k < 3; ++k) {
                lr.bbox_min[k] = (float)c->bbox_min[k];
                lr.bbox_max[k] = (float)c->bbox_max[k];
            }
            e = lv->e0 + c->error;
            bytes = mc->size;
            chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_MESH, .flags = base_chunk->desc.flags,
                                                 .object = base_chunk->desc.object, .lod = (uint16_t)L,
                                                 .encoding = mc->encoding, .decoded_size = mc->decoded_size},
                                        .data = mc->data, .size = mc->size};
        }
        lr.error = mesoi_f32_up(e);
        meso_level_record_encode(&lr, lv->lods + (size_t)MESO_LODS_RECORD_SIZE * L);
        lv->error[L] = lr.error;
        lv->triangles[L] = lm->triangle_count;
        cJSON* o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "lod", L);
        cJSON_AddStringToObject(o, "form", native ? "native" : "mesh");
        cJSON_AddNumberToObject(o, "error", (double)lr.error);
        cJSON_AddNumberToObject(o, "triangles", lm->triangle_count);
        cJSON_AddNumberToObject(o, "mesh_bytes", (double)bytes);
        cJSON_AddItemToArray(jl, o);
    }
    chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_LODS, .dtype = MESO_DTYPE_BYTES, .components = 1,
                                         .dims = {total, 1, 1}},
                                .data = lv->lods, .size = (size_t)MESO_LODS_RECORD_SIZE * total};
    return n;
}

void mesoi_standin_levels_free(mesoi_standin_levels* lv)
{
    meso_mesh_levels_free(lv->chain, lv->chain_count);
    for (uint32_t k = 0; k < MESOI_STANDIN_MAX_LEVELS; ++k)
        free(lv->chunk[k].data);
    memset(lv, 0, sizeof *lv);
}
