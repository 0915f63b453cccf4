/*
 * bake_shell_texture.c — the texture function of a shell bake
 * (meso_bake_shell --texture): the SPEC sampled (texture_function.h), its
 * distance map (distance_map.h), and texture coordinates per vertex, split
 * at uv seams (FORMAT.md §7.2, "Shell prisms and texture space"); with
 * --frames, every frame of a time-dependent built-in and its distance map
 * (FORMAT.md §7.2 "Animated texture functions";
 * volume-textures-lp-averaged-shells.md §6).
 */
#include "bake_shell.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "memory_budget.h"
#include "meso_clock.h"
#include "standin_levels.h"
#include "volume_levels.h"

void mesoi_shell_texture_free(mesoi_shell_texture* tx)
{
    meso_texfn_free(&tx->fn);
    meso_distmap_free(&tx->dist);
    free(tx->uvs);
    free(tx->source);
    free(tx->indices);
    free(tx->fn_frames);
    free(tx->dist_frames);
    mesoi_height_levels_free(tx->native, tx->native_count);
    tx->native_count = 0;
}

/* Frames 1..N-1 of an animated texture (frame 0 is tx->fn and tx->dist,
 * copied in first): each sampled at time + k / fps and its distance map
 * built at frame 0's resolution, exactly as a static bake at that time
 * would (volume-textures-lp-averaged-shells.md §6). */
static meso_result bake_frames(mesoi_bake_run* run, const meso_bake_shell_options* a, mesoi_shell_texture* tx,
                               meso_error* err)
{
    const size_t fs = tx->fn.encoded_size, ds = tx->dist.encoded_size, n = a->frames;
    meso_result r = meso_budget_check(meso_size_mul(n, meso_size_add(fs, ds)), run->common.max_memory,
                                      MESO_LIMIT_ISSUE_REQUEST, err, "%u frames of %s", a->frames, a->texture);
    if (r != MESO_OK)
        return r;
    const double t0 = meso_seconds();
    tx->fn_frames = malloc(fs * n);
    tx->dist_frames = malloc(ds * n);
    if (!tx->fn_frames || !tx->dist_frames)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "frames: out of memory");
    memcpy(tx->fn_frames, tx->fn.encoded, fs);
    memcpy(tx->dist_frames, tx->dist.encoded, ds);
    for (size_t k = 1; r == MESO_OK && k < n; ++k) {
        meso_texfn fn = {0};
        meso_distmap dist = {0};
        r = meso_texfn_from_spec_at(a->texture, a->time + (double)k / a->fps, run->common.max_memory, &fn, err);
        if (r == MESO_OK)
            r = meso_distmap_build(&fn, tx->dist.dims, a->dist_dtype, run->common.threads, &dist, err);
        if (r == MESO_OK && (fn.encoded_size != fs || dist.encoded_size != ds))
            r = meso_bake_fail(err, MESO_ERR_CORRUPT, 0, "frame %zu: texture size changed", k);
        if (r == MESO_OK) {
            memcpy(tx->fn_frames + k * fs, fn.encoded, fs);
            memcpy(tx->dist_frames + k * ds, dist.encoded, ds);
        }
        meso_texfn_free(&fn);
        meso_distmap_free(&dist);
    }
    if (r == MESO_OK)
        mesoi_run_stage(run, "frames", 0.1, 0.1, "%u frames at %g fps from t = %g s (%.0f ms)", a->frames, a->fps,
                        a->time, 1e3 * (meso_seconds() - t0));
    return r;
}

/* The native coarser levels of a static height field (height_field_levels.h)
 * or volume (volume_levels.h, whose errors bake_shell.c measures once the
 * directors are known):
 * `--levels` 0 as many as there may be, K >= 3 at most K - 2 (level 0 and
 * the base mesh come first, as for cells), else none. They stop where the
 * sup reaches the highest texel of an exterior shell (1 for the other
 * kinds, whose surface may reach w = 1: bake_shell.c texel_max), beyond
 * which the base mesh alone is as close (bake_shell.c also drops any whose
 * error reaches the base mesh's, once the directors are known). */
static meso_result native_levels(mesoi_bake_run* run, const meso_bake_shell_options* a, mesoi_shell_texture* tx,
                                 meso_error* err)
{
    const uint32_t want = mesoi_native_wanted(a->levels, MESOI_HEIGHT_MAX_NATIVE);
    if (a->frames || want == 0)
        return MESO_OK;
    if (tx->fn.kind == MESO_TEXFN_DENSITY) {
        const double t = meso_seconds();
        const meso_result r = mesoi_volume_levels_build(&tx->fn, &tx->dist, want, run->common.threads, tx->native,
                                                        &tx->native_count, err);
        if (r == MESO_OK && tx->native_count)
            mesoi_run_stage(run, "texture levels", 0.05, 0.05, "volume halved %u times, down to %ux%ux%u (%.0f ms)",
                            tx->native_count, tx->native[tx->native_count - 1].fn.dims[0],
                            tx->native[tx->native_count - 1].fn.dims[1], tx->native[tx->native_count - 1].fn.dims[2],
                            1e3 * (meso_seconds() - t));
        return r;
    }
    double hmax = 1.0;
    if (a->kind == MESO_SHELL_EXTERIOR) {
        hmax = 0.0;
        for (size_t i = 0; i < (size_t)tx->fn.dims[0] * tx->fn.dims[1]; ++i)
            hmax = fmax(hmax, (double)tx->fn.values[i]);
    }
    const double t = meso_seconds();
    const meso_result r = mesoi_height_levels_build(&tx->fn, &tx->dist, want, hmax, run->common.threads,
                                                       tx->native, &tx->native_count, err);
    if (r == MESO_OK && tx->native_count)
        mesoi_run_stage(run, "texture levels", 0.05, 0.05,
                        "height field halved %u times, down to %ux%u, heights within %g of level 0's (%.0f ms)",
                        tx->native_count, tx->native[tx->native_count - 1].fn.dims[0],
                        tx->native[tx->native_count - 1].fn.dims[1], tx->native[tx->native_count - 1].sup,
                        1e3 * (meso_seconds() - t));
    return r;
}

/* Parse the spec, sample the function, bake its distance map. */
meso_result mesoi_shell_texture_prepare(mesoi_bake_run* run, const meso_bake_shell_options* a, mesoi_shell_texture* tx,
                                        meso_error* err)
{
    double t = meso_seconds();
    meso_result r = meso_texfn_from_spec_at(a->texture, a->time, run->common.max_memory, &tx->fn, err);
    if (r != MESO_OK)
        return r;
    const uint32_t* td = tx->fn.dims;
    mesoi_run_stage(run, "texture", 0.05, 0.05, "texture %s: %s %ux%ux%u %s (%.0f ms)", a->texture,
                    tx->fn.kind == MESO_TEXFN_HEIGHT ? "height field" : "density volume", td[0], td[1], td[2],
                    tx->fn.dtype == MESO_DTYPE_U8 ? "u8" : "u16", 1e3 * (meso_seconds() - t));
    uint32_t res[3] = {a->dist_res[0], a->dist_res[1], a->dist_res[2]};
    if (!res[0])
        meso_distmap_default_res(&tx->fn, res);
    /* Limits up front: the texture is held, the distance map not yet made. */
    const uint64_t cells = (uint64_t)res[0] * res[1] * res[2];
    const uint64_t texels = (uint64_t)td[0] * td[1] * td[2];
    /* A height field's native levels (native_levels) hold at most a third
     * more: each level a quarter of the one before, its map an eighth. */
    uint64_t need = meso_size_add(meso_texture_estimate(texels), meso_distmap_estimate(cells));
    if (tx->fn.kind == MESO_TEXFN_HEIGHT && !a->frames && mesoi_native_wanted(a->levels, MESOI_HEIGHT_MAX_NATIVE))
        need = meso_size_add(need, need / 3);
    r = meso_budget_check(need,
                          run->common.max_memory, MESO_LIMIT_ISSUE_REQUEST, err,
                          "distance map %ux%ux%u (%s) of a %ux%ux%u texture", res[0], res[1], res[2],
                          a->dist_res[0] ? "--dist-res" : "default", td[0], td[1], td[2]);
    if (r != MESO_OK)
        return r;
    t = meso_seconds();
    tx->dist_type = a->dist_dtype == MESO_DTYPE_F32 ? "f32" : a->dist_dtype == MESO_DTYPE_U16 ? "u16" : "u8";
    r = meso_distmap_build(&tx->fn, res, a->dist_dtype, run->common.threads, &tx->dist, err);
    if (r == MESO_OK)
        mesoi_run_stage(run, "distance map", 0.1, 0.1,
                        "distance map %ux%ux%u %s (%s): %llu of %llu cells touch the solid (%.0f ms)", res[0], res[1],
                        res[2], tx->dist_type, a->dist_res[0] ? "--dist-res" : "default",
                        (unsigned long long)tx->dist.solid_cells, (unsigned long long)res[0] * res[1] * res[2],
                        1e3 * (meso_seconds() - t));
    if (r == MESO_OK && a->frames)
        r = bake_frames(run, a, tx, err);
    if (r == MESO_OK)
        r = native_levels(run, a, tx, err);
    return r;
}

/* Per-corner uvs into one uv per vertex: each distinct (vertex, corner uv)
 * pair (exact float bits) becomes one output vertex. Vertex v keeps index v
 * and the uv of its first corner (faces in order, corners in order); every
 * further uv it has appends a copy, numbered from nv in order of first
 * appearance. A vertex no face uses keeps its per-vertex uv. Copies share
 * position and director, so the shell stays closed across the seam. */
static meso_result split_seams(const meso_bake_shell_options* a, const meso_mesh* m, mesoi_shell_texture* tx,
                               meso_error* err)
{
    const uint32_t nv = m->vertex_count, none = UINT32_MAX;
    const size_t nc = 3 * (size_t)m->triangle_count, cap = (size_t)nv + nc; /* < 2^32: the reader's limits */
    uint32_t* next = malloc(sizeof(uint32_t) * cap); /* next copy of the same vertex, or `none` */
    float* uv = malloc(sizeof(float) * 2 * cap);
    uint8_t* used = calloc(nv ? nv : 1, 1);
    tx->source = malloc(sizeof(uint32_t) * cap);
    tx->indices = malloc(sizeof(uint32_t) * (nc ? nc : 1));
    meso_result r = next && uv && used && tx->source && tx->indices ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    uint32_t n = nv;
    for (uint32_t v = 0; r == MESO_OK && v < nv; ++v) {
        next[v] = none;
        tx->source[v] = v;
        memcpy(uv + 2 * (size_t)v, m->uvs + 2 * (size_t)v, 2 * sizeof(float));
    }
    for (size_t c = 0; r == MESO_OK && c < nc; ++c) {
        const uint32_t v = m->indices[c];
        const float* cu = m->corner_uvs + 2 * c;
        uint32_t o = v, last = v;
        if (!used[v]) {
            used[v] = 1;
            memcpy(uv + 2 * (size_t)v, cu, 2 * sizeof(float));
        }
        while (o != none && memcmp(uv + 2 * (size_t)o, cu, 2 * sizeof(float)) != 0) {
            last = o;
            o = next[o];
        }
        if (o == none) {
            o = n++;
            next[last] = o;
            next[o] = none;
            tx->source[o] = v;
            memcpy(uv + 2 * (size_t)o, cu, 2 * sizeof(float));
        }
        tx->indices[c] = o;
    }
    if (r == MESO_OK) {
        tx->uvs = malloc(sizeof(float) * 2 * (size_t)n);
        r = tx->uvs ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    }
    for (size_t o = 0; r == MESO_OK && o < n; ++o) {
        tx->uvs[2 * o] = (float)(uv[2 * o] * a->tiling[0]);
        tx->uvs[2 * o + 1] = (float)(uv[2 * o + 1] * a->tiling[1]);
    }
    tx->seam_vertices = n - nv;
    free(next);
    free(uv);
    free(used);
    return r == MESO_OK ? MESO_OK : meso_bake_fail(err, r, 0, "out of memory");
}

/* Texture coordinates: the mesh's own times the tiling (split at seams when
 * the mesh has per-corner uvs), or (documented fallback) a planar projection
 * onto the two largest bounding-box extents, the longest spanning U tiles and
 * the other V/U as densely. */
meso_result mesoi_shell_texture_uvs(mesoi_bake_run* run, const meso_bake_shell_options* a, const meso_mesh* m,
                                    const double lo[3], const double hi[3], mesoi_shell_texture* tx, meso_error* err)
{
    const uint32_t nv = m->vertex_count;
    tx->uv_source = "mesh";
    if (m->corner_uvs)
        return split_seams(a, m, tx, err);
    tx->uvs = malloc(sizeof(float) * 2 * (size_t)nv);
    if (!tx->uvs)
        return meso_bake_fail(err, MESO_ERR_OUT_OF_MEMORY, 0, "out of memory");
    if (m->uvs) {
        for (size_t v = 0; v < nv; ++v) {
            tx->uvs[2 * v] = (float)(m->uvs[2 * v] * a->tiling[0]);
            tx->uvs[2 * v + 1] = (float)(m->uvs[2 * v + 1] * a->tiling[1]);
        }
        return MESO_OK;
    }
    int ax[3] = {0, 1, 2}; /* by decreasing extent; ties keep x, y, z order */
    for (int i = 0; i < 3; ++i)
        for (int j = i + 1; j < 3; ++j)
            if (hi[ax[j]] - lo[ax[j]] > hi[ax[i]] - lo[ax[i]]) {
                const int k = ax[i];
                ax[i] = ax[j];
                ax[j] = k;
            }
    const double ext = hi[ax[0]] - lo[ax[0]] > 0 ? hi[ax[0]] - lo[ax[0]] : 1.0;
    for (size_t v = 0; v < nv; ++v) {
        tx->uvs[2 * v] = (float)((m->positions[3 * v + (size_t)ax[0]] - lo[ax[0]]) / ext * a->tiling[0]);
        tx->uvs[2 * v + 1] = (float)((m->positions[3 * v + (size_t)ax[1]] - lo[ax[1]]) / ext * a->tiling[1]);
    }
    tx->uv_source = "planar";
    tx->plane[0] = (char)('x' + ax[0]);
    tx->plane[1] = (char)('x' + ax[1]);
    tx->plane[2] = 0;
    mesoi_run_warning(run, 0,
                      "%s has no texture coordinates; projecting it onto its %s plane (the two largest bounding-box "
                      "extents), %c spanning %g tiles",
                      mesoi_base_name(a->input), tx->plane, tx->plane[0], a->tiling[0]);
    return MESO_OK;
}

/* META.parameters.texture and the report's "texture". */
void mesoi_shell_texture_json(cJSON* parent, const meso_bake_shell_options* a, const mesoi_shell_texture* tx,
                              int report)
{
    cJSON* o = cJSON_AddObjectToObject(parent, "texture");
    cJSON_AddStringToObject(o, "spec", a->texture);
    cJSON_AddStringToObject(o, "kind", tx->fn.kind == MESO_TEXFN_HEIGHT ? "height" : "density");
    const double tex_dims[3] = {tx->fn.dims[0], tx->fn.dims[1], tx->fn.dims[2]};
    cJSON_AddItemToObject(o, "texture_res",
                          cJSON_CreateDoubleArray(tex_dims, tx->fn.kind == MESO_TEXFN_HEIGHT ? 2 : 3));
    cJSON_AddItemToObject(o, "tiling", cJSON_CreateDoubleArray(a->tiling, 2));
    const double dd[3] = {tx->dist.dims[0], tx->dist.dims[1], tx->dist.dims[2]};
    cJSON_AddItemToObject(o, "dist_res", cJSON_CreateDoubleArray(dd, 3));
    cJSON_AddStringToObject(o, "dist_type", tx->dist_type);
    cJSON_AddStringToObject(o, "uv_source", tx->uv_source);
    if (tx->plane[0])
        cJSON_AddStringToObject(o, "uv_plane", tx->plane);
    if (meso_texfn_period(a->texture) > 0) {
        cJSON_AddNumberToObject(o, "time", a->time);
        if (a->frames) {
            cJSON_AddNumberToObject(o, "frames", a->frames);
            cJSON_AddNumberToObject(o, "fps", a->fps);
        }
    }
    if (report) {
        cJSON_AddNumberToObject(o, "dist_solid_cells", (double)tx->dist.solid_cells);
        cJSON_AddNumberToObject(o, "seam_vertices", tx->seam_vertices);
    }
}
