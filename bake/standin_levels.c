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

/* A simplified level's points show what the base stand-in's vertex
 * colours show there: they are interpolated at the nearest point of it
 * (cheaper than asking the kind again, and as coarse levels should be,
 * smoothed once more). */
static void base_at(const mesoi_appearance* a, mesoi_tri_grid* grid, uint32_t t, const double b[3], const double p[3],
                    float out[7])
{
    (void)grid;
    (void)p;
    const meso_mesh* base = ((const void* const*)a->ctx)[0];
    const float* shows = ((const void* const*)a->ctx)[1];
    const float* normals = ((const void* const*)a->ctx)[2];
    const uint32_t* ix = base->indices + 3 * (size_t)t;
    for (int k = 0; k < 4; ++k)
        out[k] = (float)(b[0] * shows[4 * (size_t)ix[0] + k] + b[1] * shows[4 * (size_t)ix[1] + k] +
                         b[2] * shows[4 * (size_t)ix[2] + k]);
    for (int k = 0; normals && k < 3; ++k)
        out[4 + k] = (float)(b[0] * normals[3 * (size_t)ix[0] + k] + b[1] * normals[3 * (size_t)ix[1] + k] +
                             b[2] * normals[3 * (size_t)ix[2] + k]);
}

meso_result mesoi_standin_colours(const meso_mesh* from, const float* shows, const float* from_normals,
                                  const meso_mesh* const* meshes, uint32_t count, double spacing, int components,
                                  int threads, uint8_t** out, float** normals_out, meso_error* err)
{
    uint32_t most = 1;
    for (uint32_t k = 0; k < count; ++k) {
        out[k] = NULL;
        if (from_normals)
            normals_out[k] = NULL;
        most = meshes[k]->vertex_count > most ? meshes[k]->vertex_count : most;
    }
    float* level = malloc(sizeof(float) * 4 * (size_t)most);
    double* xyz = malloc(sizeof(double) * 3 * ((size_t)from->vertex_count + 1));
    if (!level || !xyz) {
        free(level);
        free(xyz);
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in appearance: out of memory");
    }
    for (size_t k = 0; k < 3 * (size_t)from->vertex_count; ++k) /* a grid over `from` in double */
        xyz[k] = from->positions[k];
    double lo[3], hi[3];
    meso_mesh_bounds(from, lo, hi);
    mesoi_tri_grid g;
    meso_result r = mesoi_tri_grid_build(xyz, from->indices, from->triangle_count, lo, hi, &g, err);
    const int built = r == MESO_OK; /* a failed build has freed g */
    const void* ctx[3] = {from, shows, from_normals};
    const mesoi_appearance from_base = {.at = base_at, .ctx = ctx, .subdivisions = 8, .normals = from_normals != NULL};
    for (uint32_t k = 0; r == MESO_OK && k < count; ++k) {
        const meso_mesh* m = meshes[k];
        if (!m->vertex_count || !m->positions || !m->indices)
            continue; /* a kept chain level that could not be read back: no colours */
        float* nk = from_normals ? (normals_out[k] = malloc(sizeof(float) * 3 * m->vertex_count)) : NULL;
        if (!(out[k] = malloc((size_t)components * m->vertex_count)) || (from_normals && !nk))
            r = meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in appearance: out of memory");
        else if ((r = mesoi_vertex_appearance(m, spacing, &from_base, &g, threads, level, nk, err)) == MESO_OK)
            mesoi_appearance_encode(level, m->vertex_count, components, out[k]);
    }
    if (built)
        mesoi_tri_grid_free(&g);
    free(level);
    free(xyz);
    if (r != MESO_OK)
        for (uint32_t k = 0; k < count; ++k) {
            free(out[k]);
            out[k] = NULL;
            if (from_normals) {
                free(normals_out[k]);
                normals_out[k] = NULL;
            }
        }
    return r;
}

/* `m` with `normals` as its MESH chunk (raw) into *out, whose old bytes are
 * freed. */
static meso_result encode_with_normals(const meso_mesh* m, float* normals, meso_mesh_chunk* out,
                                       meso_error* err)
{
    meso_mesh with = *m;
    with.normals = normals;
    meso_mesh_chunk c = {0};
    const meso_result r = meso_bake_mesh_chunk(&with, NULL, &c, err);
    if (r == MESO_OK) {
        free(out->data);
        *out = c;
    }
    return r;
}

meso_result mesoi_standin_levels_appearance(mesoi_standin_levels* lv, const meso_mesh* base, double spacing,
                                            const mesoi_appearance* a, int threads, meso_error* err)
{
    const int nc = lv->vcol_components = a->occlusion_only ? 1 : 4;
    lv->shows = malloc(sizeof(float) * 4 * ((size_t)base->vertex_count + 1));
    if (!lv->shows || !(lv->vcol[0] = malloc((size_t)nc * base->vertex_count + 1)))
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in appearance: out of memory");
    if (a->normals && !(lv->normals = malloc(sizeof(float) * 3 * ((size_t)base->vertex_count + 1))))
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "stand-in appearance: out of memory");
    meso_result r = mesoi_vertex_appearance(base, spacing, a, NULL, threads, lv->shows, lv->normals, err);
    if (r == MESO_OK)
        mesoi_appearance_encode(lv->shows, base->vertex_count, nc, lv->vcol[0]);
    /* The simplified levels: at the nearest point of the base mesh. */
    const meso_mesh* chain[MESOI_STANDIN_MAX_LEVELS];
    float* chain_normals[MESOI_STANDIN_MAX_LEVELS] = {NULL};
    for (uint32_t S = 1; S < lv->count; ++S)
        chain[S - 1] = &lv->chain[S - 1].mesh;
    if (r == MESO_OK && lv->count > 1)
        r = mesoi_standin_colours(base, lv->shows, lv->normals, chain, lv->count - 1, spacing, nc, threads,
                                  lv->vcol + 1, chain_normals, err);
    /* The MESH chunks again, with the baked normals: level 1's its own
     * (it shared level 0's bytes), the chain's in place. */
    if (r == MESO_OK && lv->normals)
        r = encode_with_normals(lv->standin_mesh ? lv->standin_mesh : base, lv->normals, &lv->l1_chunk, err);
    for (uint32_t k = 0; r == MESO_OK && lv->normals && k + 1 < lv->count; ++k)
        if (chain_normals[k] && chain[k]->vertex_count)
            r = encode_with_normals(chain[k], chain_normals[k], &lv->chunk[k], err);
    for (uint32_t k = 0; k + 1 < lv->count; ++k)
        free(chain_normals[k]);
    return r;
}

/* The VCOL chunk of stand-in S at lod L. */
static mesoi_chunk vcol_chunk(const mesoi_standin_levels* lv, uint32_t S, const meso_mesh* m, uint32_t object,
                              uint16_t L)
{
    const uint16_t nc = (uint16_t)lv->vcol_components;
    return (mesoi_chunk){.desc = {.type = MESO_CHUNK_VCOL, .object = object, .lod = L, .dtype = MESO_DTYPE_U8,
                                  .components = nc, .dims = {m->vertex_count, 1, 1}},
                         .data = lv->vcol[S], .size = nc * (size_t)m->vertex_count};
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
        const meso_mesh* l1 = lv->standin_mesh ? lv->standin_mesh : base;
        const mesoi_chunk* c1 = lv->standin_chunk ? lv->standin_chunk : base_chunk;
        const meso_mesh* own = native && L ? lv->native_mesh[L - 1] : NULL;
        const meso_mesh* lm = own ? own : native ? base : S == 1 ? l1 : &lv->chain[S - 2].mesh;
        size_t bytes = own ? lv->native_mesh_bytes[L - 1] : native ? base_chunk->size : c1->size, vbytes = 0;
        double e = 0;
        if (native) {
            const int own_box = L && lv->native_bbox[L - 1];
            memcpy(lr.bbox_min, own_box ? lv->native_min[L - 1] : l0_min, sizeof lr.bbox_min);
            memcpy(lr.bbox_max, own_box ? lv->native_max[L - 1] : l0_max, sizeof lr.bbox_max);
            e = L ? lv->native_error[L - 1] : 0;
        } else if (S == 1) {
            double lo[3], hi[3];
            meso_mesh_bounds(l1, lo, hi);
            for (int k = 0; k < 3; ++k) {
                lr.bbox_min[k] = (float)lo[k];
                lr.bbox_max[k] = (float)hi[k];
            }
            e = lv->e0;
            chunks[n] = *c1;
            chunks[n].desc.lod = (uint16_t)L;
            if (lv->l1_chunk.data) { /* its own bytes: the baked normals */
                chunks[n].data = lv->l1_chunk.data;
                chunks[n].size = bytes = lv->l1_chunk.size;
                chunks[n].desc.encoding = lv->l1_chunk.encoding;
                chunks[n].desc.decoded_size = lv->l1_chunk.decoded_size;
            }
            ++n;
            if (lv->vcol[0]) {
                chunks[n] = vcol_chunk(lv, 0, l1, base_chunk->desc.object, (uint16_t)L);
                vbytes = chunks[n++].size;
            }
        } else {
            const meso_mesh_level* c = &lv->chain[S - 2];
            const meso_mesh_chunk* mc = &lv->chunk[S - 2];
            for (int k = 0; k < 3; ++k) {
                lr.bbox_min[k] = (float)c->bbox_min[k];
                lr.bbox_max[k] = (float)c->bbox_max[k];
            }
            e = (lv->chain_e0 > 0 ? lv->chain_e0 : lv->e0) + c->error;
            bytes = mc->size;
            chunks[n++] = (mesoi_chunk){.desc = {.type = MESO_CHUNK_MESH, .flags = base_chunk->desc.flags,
                                                 .object = base_chunk->desc.object, .lod = (uint16_t)L,
                                                 .encoding = mc->encoding, .decoded_size = mc->decoded_size},
                                        .data = mc->data, .size = mc->size};
            if (lv->vcol[S - 1]) {
                chunks[n] = vcol_chunk(lv, S - 1, &c->mesh, base_chunk->desc.object, (uint16_t)L);
                vbytes = chunks[n++].size;
            }
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
        if (vbytes)
            cJSON_AddNumberToObject(o, "colour_bytes", (double)vbytes);
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
    for (uint32_t k = 0; k < MESOI_STANDIN_MAX_LEVELS; ++k) {
        free(lv->chunk[k].data);
        free(lv->vcol[k]);
    }
    free(lv->shows);
    free(lv->normals);
    free(lv->l1_chunk.data);
    memset(lv, 0, sizeof *lv);
}
