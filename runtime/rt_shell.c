/*
 * rt_shell.c — SHELL objects (FORMAT.md §7.2): streaming the base mesh,
 * directors and texture function of one shell into GL, and ray casting it
 * with one of three techniques (papers/smooth-and-curved-shell-mapping.md;
 * MESO_SHELL_SLICES, the slice renderer, is runtime/rt_slices.c;
 * the shaders are runtime/shaders/shell_*.glsl, their maths is spelled out
 * in runtime/reference/shell_map.h).
 *
 * GL layout, chosen so the host can animate without re-baking:
 *  - one texture buffer of 2 RGBA32F texels per vertex, (bottom.xyz, s) and
 *    (top.xyz, t'): the prism corners and texture coordinates;
 *  - one R32UI texture buffer of triangle indices;
 *  - the texture function (2D height or 3D density) and the distance map.
 * The hull (or tetrahedra) triangles are generated in the vertex shader
 * from gl_VertexID, so meso_rt_shell_update is one buffer upload: no
 * triangulation on the CPU (the paper's claim that animated meshes need no
 * precomputation holds here too).
 * The texture function can change too (volume-textures-lp-averaged-shells.md
 * §6): meso_rt_shell_set_texture uploads new textures and swaps them in
 * only when complete; the frames a file stores (ANIM, TXFR, DSFR) are kept
 * on the host and meso_rt_shell_set_time uploads the one a time selects.
 */
#include "rt_internal.h"
#include "shaders_embedded.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static void shell_free(meso_rt* rt, mesoi_shell* s)
{
    if (!s)
        return;
    mesoi_gl* gl = &rt->gl;
    GLuint tex[7] = {s->vert_tex, s->index_tex, s->func_tex, s->dist_tex, s->color_tex, s->order_tex, s->adj_tex};
    GLuint buf[4] = {s->vert_buf, s->index_buf, s->order_buf, s->adj_buf};
    gl->DeleteTextures(7, tex);
    gl->DeleteBuffers(4, buf);
    mesoi_rt_free(rt, s->neighbours);
    mesoi_rt_free(rt, s->mates);
    mesoi_rt_free(rt, s->positions);
    mesoi_rt_free(rt, s->directors);
    mesoi_rt_free(rt, s->uvs);
    mesoi_rt_free(rt, s->fn_frames);
    mesoi_rt_free(rt, s->dist_frames);
    mesoi_rt_free(rt, s->indices);
    mesoi_rt_free(rt, s);
}

void mesoi_shell_release(meso_rt* rt, mesoi_object* o)
{
    shell_free(rt, o->shell);
    o->shell = NULL;
}

/* (bottom.xyz, s), (top.xyz, t') per vertex, FORMAT.md §7.2; and the box
 * of the corners. */
static void fill_vertex_texels(mesoi_shell* s, float* out)
{
    for (int k = 0; k < 3; ++k) {
        s->box_min[k] = INFINITY;
        s->box_max[k] = -INFINITY;
    }
    for (uint32_t v = 0; v < s->vertex_count; ++v) {
        const float* p = s->positions + 3 * (size_t)v;
        const float* d0 = s->directors + 3 * (size_t)v;
        const float* d1 = s->layers == 2 ? s->directors + 3 * ((size_t)s->vertex_count + v) : NULL;
        float* o = out + 8 * (size_t)v;
        for (int k = 0; k < 3; ++k) {
            o[k] = d1 ? p[k] + d1[k] : p[k];
            o[4 + k] = p[k] + d0[k];
        }
        o[3] = s->uvs[2 * (size_t)v];
        o[7] = s->uvs[2 * (size_t)v + 1];
        for (int k = 0; k < 3; ++k) {
            s->box_min[k] = fminf(s->box_min[k], fminf(o[k], o[4 + k]));
            s->box_max[k] = fmaxf(s->box_max[k], fmaxf(o[k], o[4 + k]));
        }
    }
}

/* Whether any point of the box (object space) may lie on the eye's side of
 * the near plane (shell_vert.glsl reaches_near) for ds's mvp: one corner
 * there is enough, as the side away from the eye is convex. */
static int box_reaches_near(const mesoi_draw* ds, const float* model, const float lo[3], const float hi[3])
{
    /* clip z's and w's rows of pv · model (model all zero: identity) */
    int identity = 1;
    for (int i = 0; i < 16; ++i)
        identity = identity && model[i] == 0.0f;
    double row[2][4];
    for (int r = 0; r < 2; ++r)
        for (int c = 0; c < 4; ++c) {
            double v = 0.0;
            for (int k = 0; k < 4; ++k)
                v += ds->pv[4 * k + 2 + r] * (identity ? (double)(k == c) : (double)model[4 * c + k]);
            row[r][c] = v;
        }
    const double sgn = ds->depth_ndc[0] > ds->depth_ndc[2] ? -1.0 : 1.0;
    for (int c = 0; c < 8; ++c) {
        const double p[3] = {c & 1 ? hi[0] : lo[0], c & 2 ? hi[1] : lo[1], c & 4 ? hi[2] : lo[2]};
        double z = row[0][3], w = row[1][3];
        for (int k = 0; k < 3; ++k) {
            z += row[0][k] * p[k];
            w += row[1][k] * p[k];
        }
        if (!(sgn * (z - ds->depth_ndc[0] * w) >= 0.0)) /* NaN: may */
            return 1;
    }
    return 0;
}

/* The stored frames of an animated texture function (FORMAT.md §7.2
 * "Animated texture functions"): the ANIM record, TXFR and (with a DIST)
 * DSFR read to host memory and checked against the frame-0 chunks. */
static meso_result load_frames(meso_rt* rt, meso_file* f, uint32_t id, mesoi_shell* s, int32_t ti, int32_t xi)
{
    const int32_t ai = mesoi_find_chunk(rt, f, MESO_CHUNK_ANIM, id), fi = mesoi_find_chunk(rt, f, MESO_CHUNK_TXFR, id);
    const int32_t si = mesoi_find_chunk(rt, f, MESO_CHUNK_DSFR, id);
    if (ai < 0)
        return MESO_OK;
    void* rec = NULL;
    size_t rec_size = 0;
    meso_result r = mesoi_read_whole(rt, f, ai, &rec, &rec_size); /* contents checked: 4901, 4902 */
    if (r != MESO_OK)
        return r;
    meso_anim_record a;
    meso_anim_record_decode(rec, &a);
    mesoi_rt_free(rt, rec);
    const meso_chunk_info *tc = ti >= 0 ? meso_file_chunk(f, (uint32_t)ti) : NULL,
                          *fc = fi >= 0 ? meso_file_chunk(f, (uint32_t)fi) : NULL;
    const meso_chunk_info *xc = xi >= 0 ? meso_file_chunk(f, (uint32_t)xi) : NULL,
                          *sc = si >= 0 ? meso_file_chunk(f, (uint32_t)si) : NULL;
    int ok = tc && fc && (!xc) == (!sc) && fc->dtype == tc->dtype && fc->components == 1 &&
             fc->dims[0] == tc->dims[0] && fc->dims[1] == tc->dims[1] &&
             (uint64_t)fc->dims[2] == (uint64_t)tc->dims[2] * a.frame_count;
    if (ok && xc)
        ok = sc->dtype == xc->dtype && sc->components == 1 && sc->dims[0] == xc->dims[0] &&
             sc->dims[1] == xc->dims[1] && (uint64_t)sc->dims[2] == (uint64_t)xc->dims[2] * a.frame_count;
    if (!ok) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "shell %u: ANIM needs TXFR (and DSFR with a DIST) of %u frames of its texture function (FORMAT.md "
                  "issue 6105)",
                  id, a.frame_count);
        return MESO_ERR_CORRUPT;
    }
    void *fn = NULL, *dist = NULL;
    size_t fn_size = 0, dist_size = 0;
    r = mesoi_read_whole(rt, f, fi, &fn, &fn_size);
    if (r == MESO_OK && sc)
        r = mesoi_read_whole(rt, f, si, &dist, &dist_size);
    if (r != MESO_OK) {
        mesoi_rt_free(rt, fn);
        return r;
    }
    s->anim = a;
    s->fn_frames = fn;
    s->dist_frames = dist;
    s->fn_bytes = fn_size / a.frame_count;
    s->dist_bytes = dist_size / a.frame_count;
    meso_rt_shell_texture* d = &s->frame_desc;
    d->kind = tc->type == MESO_CHUNK_TX2D ? MESO_RT_TEXTURE_HEIGHT : MESO_RT_TEXTURE_DENSITY;
    memcpy(d->dims, tc->dims, sizeof(d->dims));
    d->dtype = tc->dtype;
    if (xc) {
        memcpy(d->dist_dims, xc->dims, sizeof(d->dist_dims));
        d->dist_dtype = xc->dtype;
    }
    s->shown_frame = 0; /* the TX2D/TX3D and DIST just uploaded */
    return MESO_OK;
}

/* The shell's colour (FORMAT.md §7.2 "Shell colour"): COLR uploaded as
 * SRGB8_ALPHA8 and the CMAP record's scale. No COLR: nothing (u_albedo). */
static meso_result load_color(meso_rt* rt, meso_file* f, uint32_t id, mesoi_shell* s)
{
    const int32_t ci = mesoi_find_chunk(rt, f, MESO_CHUNK_COLR, id), mi = mesoi_find_chunk(rt, f, MESO_CHUNK_CMAP, id);
    if (ci < 0 && mi < 0)
        return MESO_OK;
    const meso_chunk_info* c = ci >= 0 ? meso_file_chunk(f, (uint32_t)ci) : NULL;
    if (!c || mi < 0 || c->dtype != MESO_DTYPE_U8 || c->components != 4 ||
        (c->dims[2] != 1 && s->tex_kind != 2)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "shell %u: colour needs one U8 x 4 COLR (3D only over a TX3D) and its CMAP record (FORMAT.md "
                  "issue 6106)",
                  id);
        return MESO_ERR_CORRUPT;
    }
    void* rec = NULL;
    size_t rec_size = 0;
    meso_result r = mesoi_read_whole(rt, f, mi, &rec, &rec_size); /* contents checked: 4911, 4912 */
    if (r != MESO_OK)
        return r;
    meso_cmap_record m;
    meso_cmap_record_decode(rec, &m);
    mesoi_rt_free(rt, rec);
    void* texels = NULL;
    size_t size = 0;
    r = mesoi_read_whole(rt, f, ci, &texels, &size);
    if (r == MESO_OK)
        r = mesoi_upload_srgba8(rt, c->dims, 1, texels, &s->color_tex);
    mesoi_rt_free(rt, texels);
    s->color_scale[0] = m.scale[0];
    s->color_scale[1] = m.scale[1];
    s->color_scale[2] = 1.0f;
    return r;
}

meso_result mesoi_shell_load(meso_rt* rt, meso_file* f, uint32_t id, mesoi_object* o)
{
    const int32_t mi = mesoi_find_chunk(rt, f, MESO_CHUNK_MESH, id), di = mesoi_find_chunk(rt, f, MESO_CHUNK_SDIR, id);
    if (mi < 0 || di < 0) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND, "shell %u lacks its %s chunk", id,
                  mi < 0 ? "MESH" : "SDIR");
        return MESO_ERR_NOT_FOUND;
    }
    const int32_t hi = mesoi_find_chunk(rt, f, MESO_CHUNK_TX2D, id), vi = mesoi_find_chunk(rt, f, MESO_CHUNK_TX3D, id);
    const int32_t xi = mesoi_find_chunk(rt, f, MESO_CHUNK_DIST, id);
    mesoi_shell* s = mesoi_rt_alloc(rt, sizeof(*s));
    if (!s)
        return MESO_ERR_OUT_OF_MEMORY;
    memset(s, 0, sizeof(*s));
    void* mesh = NULL;
    size_t mesh_size = 0;
    meso_result r = mesoi_read_whole(rt, f, mi, &mesh, &mesh_size);
    meso_mesh_view mv;
    meso_error err;
    if (r == MESO_OK && (r = meso_mesh_parse(mesh, mesh_size, &mv, &err)) != MESO_OK)
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "%s", err.message);
    const meso_chunk_info* dc = meso_file_chunk(f, (uint32_t)di);
    if (r == MESO_OK) {
        s->vertex_count = mv.layout.vertex_count;
        s->triangle_count = mv.layout.index_count / 3;
        s->layers = dc->dims[1];
        if (dc->dtype != MESO_DTYPE_F32 || dc->components != 3 || dc->dims[0] != s->vertex_count ||
            (s->layers != 1 && s->layers != 2) || dc->dims[2] != 1 || s->triangle_count == 0) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "shell %u: SDIR is %ux%ux%u F32x3? (dtype %u x %u) for a MESH of %u vertices and %u "
                      "triangles; FORMAT.md §7.2 wants N x 1|2 x 1 with N the vertex count",
                      id, dc->dims[0], dc->dims[1], dc->dims[2], dc->dtype, dc->components, s->vertex_count,
                      s->triangle_count);
            r = MESO_ERR_CORRUPT;
        }
    }
    GLint max_texels = 0;
    rt->gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_texels);
    if (r == MESO_OK && ((uint64_t)s->vertex_count * 2 > (uint64_t)max_texels ||
                         (uint64_t)s->triangle_count * 3 > (uint64_t)max_texels ||
                         (uint64_t)s->triangle_count * 36 > (uint64_t)INT32_MAX)) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "shell %u: %u vertices / %u triangles exceed this context's texture buffer size (%d texels)",
                  id, s->vertex_count, s->triangle_count, max_texels);
        r = MESO_ERR_UNSUPPORTED;
    }
    void* dirs = NULL;
    size_t dirs_size = 0;
    if (r == MESO_OK)
        r = mesoi_read_whole(rt, f, di, &dirs, &dirs_size);
    const size_t nv = s->vertex_count;
    /* Non-finite directors would send every ray through a prism with NaN
     * corners (FORMAT.md issue 6102); MESH values were checked by the read. */
    for (size_t k = 0; r == MESO_OK && k < dirs_size / sizeof(float); ++k)
        if (!isfinite(((const float*)dirs)[k])) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "shell %u: SDIR value %zu is not finite (FORMAT.md issue 6102)", id, k);
            r = MESO_ERR_CORRUPT;
        }
    if (r != MESO_OK)
        mesoi_rt_free(rt, dirs);
    if (r == MESO_OK) {
        s->directors = dirs;
        s->positions = mesoi_rt_alloc(rt, sizeof(float) * 3 * nv);
        s->uvs = mesoi_rt_alloc(rt, sizeof(float) * 2 * nv);
        if (!s->positions || !s->uvs)
            r = MESO_ERR_OUT_OF_MEMORY;
    }
    float* texels = NULL;
    if (r == MESO_OK) {
        memcpy(s->positions, mv.positions, sizeof(float) * 3 * nv);
        if (mv.uvs)
            memcpy(s->uvs, mv.uvs, sizeof(float) * 2 * nv);
        else
            memset(s->uvs, 0, sizeof(float) * 2 * nv);
        texels = mesoi_rt_alloc(rt, sizeof(float) * 8 * nv);
        s->indices = mesoi_rt_alloc(rt, sizeof(uint32_t) * 3 * (size_t)s->triangle_count);
        if (!texels || !s->indices)
            r = MESO_ERR_OUT_OF_MEMORY;
        else
            memcpy(s->indices, mv.indices, sizeof(uint32_t) * 3 * (size_t)s->triangle_count);
        s->order_stale = 1;
    }
    const GLint prev_tex_buffer = mesoi_upload_begin(rt);
    if (r == MESO_OK) {
        fill_vertex_texels(s, texels);
        s->vert_tex = mesoi_texture_buffer(rt, GL_RGBA32F, texels, sizeof(float) * 8 * nv, &s->vert_buf);
        s->index_tex = mesoi_texture_buffer(rt, GL_R32UI, mv.indices, sizeof(uint32_t) * 3 * (size_t)s->triangle_count,
                                      &s->index_buf);
        if (rt->hull_reject_ok) {
            s->order_tex = mesoi_texture_buffer(rt, GL_R32UI, mv.indices,
                                                sizeof(uint32_t) * 3 * (size_t)s->triangle_count, &s->order_buf);
            s->neighbours = mesoi_rt_alloc(rt, sizeof(int32_t) * 3 * (size_t)s->triangle_count);
            s->mates = mesoi_rt_alloc(rt, sizeof(int32_t) * 3 * (size_t)s->triangle_count);
            r = s->neighbours && s->mates ? mesoi_prism_topology(rt, s, s->mates, &s->closed)
                                          : MESO_ERR_OUT_OF_MEMORY;
            if (r == MESO_OK)
                r = mesoi_prism_neighbours(rt, s, s->mates, s->neighbours);
            if (r == MESO_OK) /* slots = triangles until the first sort */
                s->adj_tex = mesoi_texture_buffer(rt, GL_R32I, s->neighbours,
                                                  sizeof(int32_t) * 3 * (size_t)s->triangle_count, &s->adj_buf);
        }
        if (r == MESO_OK && (!s->vert_tex || !s->index_tex || (rt->hull_reject_ok && (!s->order_tex || !s->adj_tex))))
            r = MESO_ERR_GL;
    }
    mesoi_rt_free(rt, texels);
    mesoi_rt_free(rt, mesh);
    if (r == MESO_OK && (hi >= 0 || vi >= 0)) {
        const int32_t ti = hi >= 0 ? hi : vi;
        const meso_chunk_info* tc = meso_file_chunk(f, (uint32_t)ti);
        s->tex_kind = hi >= 0 ? 1 : 2;
        for (int k = 0; k < 3; ++k)
            s->tex_size[k] = (float)tc->dims[k];
        r = mesoi_upload_texture(rt, f, ti, s->tex_kind == 2, 0, &s->func_tex);
    }
    if (r == MESO_OK && xi >= 0)
        r = mesoi_upload_texture(rt, f, xi, 1, 1, &s->dist_tex);
    if (r == MESO_OK)
        r = load_frames(rt, f, id, s, hi >= 0 ? hi : vi, xi);
    if (r == MESO_OK)
        r = load_color(rt, f, id, s);
    char what[48];
    snprintf(what, sizeof(what), "uploading shell %u", id);
    r = mesoi_upload_end(rt, prev_tex_buffer, r, what);
    if (r != MESO_OK) {
        shell_free(rt, s);
        return r;
    }
    o->shell = s;
    return MESO_OK;
}

meso_result meso_rt_shell_update(meso_rt* rt, meso_rt_object h, const float* positions, const float* directors,
                                 uint32_t vertex_count)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !o->shell || vertex_count != o->shell->vertex_count) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_shell_update: not a live shell, or vertex_count %u differs", vertex_count);
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_shell* s = o->shell;
    const size_t nv = s->vertex_count;
    if (positions)
        memcpy(s->positions, positions, sizeof(float) * 3 * nv);
    if (directors)
        memcpy(s->directors, directors, sizeof(float) * 3 * nv * s->layers);
    float* texels = mesoi_rt_alloc(rt, sizeof(float) * 8 * nv);
    if (!texels)
        return MESO_ERR_OUT_OF_MEMORY;
    fill_vertex_texels(s, texels);
    meso_result r = mesoi_buffer_update(rt, s->vert_buf, texels, sizeof(float) * 8 * nv, "meso_rt_shell_update");
    mesoi_rt_free(rt, texels);
    /* Which prisms are folded may change with the shape (rt_prism_walk.c):
     * tested again, one pass. The welded topology is kept unless a pair of
     * mates no longer shares its corners (split vertices moved apart); then
     * it is found again (a sort). Uploaded with the next sort. */
    if (r == MESO_OK && s->neighbours && !mesoi_prism_topology_holds(s, s->mates))
        r = mesoi_prism_topology(rt, s, s->mates, &s->closed);
    if (r == MESO_OK && s->neighbours)
        r = mesoi_prism_neighbours(rt, s, s->mates, s->neighbours);
    s->order_stale = 1;
    return r;
}

meso_result meso_rt_shell_info(const meso_rt* rt, meso_rt_object h, uint32_t* vertex_count, uint32_t* layers)
{
    const mesoi_object* o = mesoi_lookup(rt, h);
    if (!o)
        return MESO_ERR_INVALID_ARG;
    if (vertex_count)
        *vertex_count = o->shell ? o->shell->vertex_count : 0;
    if (layers)
        *layers = o->shell ? o->shell->layers : 0;
    return MESO_OK;
}

/* --- animated texture functions (volume-textures-lp-averaged-shells.md §6) - */

static int dist_finite(const meso_rt_shell_texture* d, size_t n)
{
    if (d->dist_dtype != MESO_DTYPE_F32)
        return 1;
    const float* v = (const float*)d->dist_data;
    for (size_t i = 0; i < n; ++i)
        if (!(v[i] >= 0.0f && v[i] <= 3.4e38f))
            return 0;
    return 1;
}

/* What is wrong with `d` for this context, or NULL. */
static const char* texture_desc_error(meso_rt* rt, const meso_rt_shell_texture* d)
{
    if (!d)
        return "desc is NULL";
    if (d->kind != MESO_RT_TEXTURE_HEIGHT && d->kind != MESO_RT_TEXTURE_DENSITY)
        return "kind is neither MESO_RT_TEXTURE_HEIGHT nor MESO_RT_TEXTURE_DENSITY";
    if (d->dtype != MESO_DTYPE_U8 && d->dtype != MESO_DTYPE_U16)
        return "dtype is not U8 or U16";
    if (!d->data)
        return "data is NULL";
    GLint max2 = 0, max3 = 0;
    rt->gl.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max2);
    rt->gl.GetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max3);
    const GLint maxd = d->kind == MESO_RT_TEXTURE_HEIGHT ? max2 : max3;
    for (int k = 0; k < 3; ++k)
        if (d->dims[k] < 1 || d->dims[k] > (uint32_t)maxd)
            return "a texture dimension is 0 or above the context's texture size limit";
    if (d->kind == MESO_RT_TEXTURE_HEIGHT && d->dims[2] != 1)
        return "a height field needs dims[2] = 1";
    const int has_dist = d->dist_dims[0] || d->dist_dims[1] || d->dist_dims[2];
    if (!has_dist)
        return d->dist_data ? "dist_data given with dist_dims 0, 0, 0" : NULL;
    for (int k = 0; k < 3; ++k)
        if (d->dist_dims[k] < 1 || d->dist_dims[k] > (uint32_t)max3)
            return "a distance-map dimension is 0 or above the context's 3D texture size limit";
    if (d->dist_dtype != MESO_DTYPE_U8 && d->dist_dtype != MESO_DTYPE_U16 && d->dist_dtype != MESO_DTYPE_F32)
        return "dist_dtype is not U8, U16 or F32";
    if (!d->dist_data)
        return "dist_data is NULL";
    if (!dist_finite(d, (size_t)d->dist_dims[0] * d->dist_dims[1] * d->dist_dims[2]))
        return "an F32 distance is not finite and >= 0";
    return NULL;
}

/* New textures first, the object's swapped in only when both uploaded:
 * on any failure the object keeps its old function and distance map. */
static meso_result replace_texture(meso_rt* rt, mesoi_shell* s, const meso_rt_shell_texture* d, const char* what)
{
    GLuint fn = 0, dist = 0;
    const GLint prev = mesoi_upload_begin(rt);
    meso_result r = mesoi_upload_texels(rt, d->dims, d->dtype, d->kind == MESO_RT_TEXTURE_DENSITY, 0, d->data, &fn);
    if (r == MESO_OK && d->dist_data)
        r = mesoi_upload_texels(rt, d->dist_dims, d->dist_dtype, 1, 1, d->dist_data, &dist);
    r = mesoi_upload_end(rt, prev, r, what);
    if (r != MESO_OK) {
        GLuint tex[2] = {fn, dist};
        rt->gl.DeleteTextures(2, tex);
        return r;
    }
    GLuint old[2] = {s->func_tex, s->dist_tex};
    rt->gl.DeleteTextures(2, old);
    s->func_tex = fn;
    s->dist_tex = dist;
    s->tex_kind = d->kind;
    for (int k = 0; k < 3; ++k)
        s->tex_size[k] = (float)d->dims[k];
    return MESO_OK;
}

meso_result meso_rt_shell_set_texture(meso_rt* rt, meso_rt_object h, const meso_rt_shell_texture* desc)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    const char* bad = !o || !o->shell ? "not a live shell" : texture_desc_error(rt, desc);
    if (bad) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_shell_set_texture: %s", bad);
        return MESO_ERR_INVALID_ARG;
    }
    const meso_result r = replace_texture(rt, o->shell, desc, "meso_rt_shell_set_texture");
    if (r == MESO_OK)
        o->shell->shown_frame = UINT32_MAX;
    return r;
}

/* Uploads stored frame k as the texture shown. */
static meso_result show_frame(meso_rt* rt, mesoi_shell* s, uint32_t k, const char* what)
{
    meso_rt_shell_texture d = s->frame_desc;
    d.data = s->fn_frames + k * s->fn_bytes;
    d.dist_data = s->dist_frames ? s->dist_frames + k * s->dist_bytes : NULL;
    const meso_result r = replace_texture(rt, s, &d, what);
    if (r == MESO_OK)
        s->shown_frame = k;
    return r;
}

meso_result meso_rt_shell_set_time(meso_rt* rt, meso_rt_object h, double seconds)
{
    mesoi_object* o = mesoi_lookup(rt, h);
    if (!o || !o->shell || !(seconds == seconds)) {
        if (rt)
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                      "meso_rt_shell_set_time: not a live shell, or the time is NaN");
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_shell* s = o->shell;
    if (!s->anim.frame_count)
        return MESO_OK;
    const uint32_t k = meso_anim_frame_at(&s->anim, seconds);
    return k == s->shown_frame ? MESO_OK : show_frame(rt, s, k, "meso_rt_shell_set_time");
}

meso_result meso_rt_shell_anim_info(const meso_rt* rt, meso_rt_object h, uint32_t* frame_count, float* fps,
                                    uint32_t* frame)
{
    const mesoi_object* o = mesoi_lookup(rt, h);
    if (!o)
        return MESO_ERR_INVALID_ARG;
    const mesoi_shell* s = o->shell;
    if (frame_count)
        *frame_count = s ? s->anim.frame_count : 0;
    if (fps)
        *fps = s && s->anim.frame_count ? s->anim.fps : 0.0f;
    if (frame)
        *frame = s && s->anim.frame_count ? s->shown_frame : UINT32_MAX;
    return MESO_OK;
}

/* --- programs ------------------------------------------------------------ */

/* Programs per technique, with or without the stats counters (atomics
 * cost time, so draws that do not ask for stats run without them). */
enum { UNIT_INSTANCES = SHELL_UNIT_COUNT, UNIT_ADJ, SHELL_UNITS_ALL };
static const char* const shell_samplers[SHELL_UNITS_ALL] = {"u_verts", "u_index", "u_height",    "u_volume",
                                                            "u_dist",  "u_color", "u_instances", "u_adj"};

static const mesoi_program* shell_program(meso_rt* rt, meso_shell_technique t, int stats, meso_rt_pass pass)
{
    mesoi_program* p = &rt->shell_programs[pass][stats][t];
    if (p->id)
        return p;
    char head[640];
    /* The image functions: core in OpenGL 4.2 and ES 3.1 (atomics ES 3.2),
     * an extension to the 330 prelude. */
    const char* reject = !rt->hull_reject_ok ? ""
                         : rt->gles          ? "#define MESO_HULL_REJECT 1\n"
                                             : "#extension GL_ARB_shader_image_load_store : require\n"
                                               "#define MESO_HULL_REJECT 1\n";
    snprintf(head, sizeof(head), "%s%s#define MESO_TECHNIQUE %d\n", mesoi_glsl_prelude(rt, stats), reject, (int)t);
    const char* vs[5] = {head, MESOI_GLSL_VERTEX_STAGE, mesoi_glsl_instance, mesoi_glsl_shell_common,
                         mesoi_glsl_shell_vert};
    const char* pre[4] = {mesoi_glsl_instance, mesoi_glsl_shell_common, mesoi_glsl_raycast_common,
                          mesoi_glsl_shell_texfn};
    static const char* const names[MESO_PASS_COUNT][MESO_SHELL_TECHNIQUE_COUNT] = {
        {"shell smooth", "shell curved", "shell tetra", "shell segment"},
        {"shell smooth depth", "shell curved depth", "shell tetra depth", "shell segment depth"},
        {"shell smooth gbuffer", "shell curved gbuffer", "shell tetra gbuffer", "shell segment gbuffer"}};
    const mesoi_program_src src = {.vs = vs, .vs_count = 5, .vs_file = "shell_vert.glsl", .pre = pre,
                                   .pre_count = 4, .frag = mesoi_glsl_shell_frag, .frag_file = "shell_frag.glsl",
                                   .name = names[pass][t], .samplers = shell_samplers,
                                   .sampler_count = SHELL_UNITS_ALL};
    return mesoi_program_build(rt, p, pass, &src);
}

meso_result mesoi_shell_prepare(meso_rt* rt, int stats, meso_rt_pass pass)
{
    for (int t = 0; t < MESO_SHELL_TECHNIQUE_COUNT; ++t)
        if (t != MESO_SHELL_SLICES && !shell_program(rt, (meso_shell_technique)t, stats, pass))
            return MESO_ERR_GL;
    return stats ? MESO_OK : mesoi_slices_prepare(rt, pass);
}

void mesoi_shell_programs_destroy(meso_rt* rt)
{
    for (int pass = 0; pass < MESO_PASS_COUNT; ++pass)
        for (int st = 0; st < 2; ++st)
            for (int t = 0; t < MESO_SHELL_TECHNIQUE_COUNT; ++t)
                mesoi_program_delete(rt, &rt->shell_programs[pass][st][t]);
    if (rt->empty_vao)
        rt->gl.DeleteVertexArrays(1, &rt->empty_vao);
    if (rt->stats_buffer)
        rt->gl.DeleteBuffers(1, &rt->stats_buffer);
    if (rt->hit_image)
        rt->gl.DeleteTextures(1, &rt->hit_image);
    mesoi_slices_destroy(rt);
    rt->empty_vao = rt->stats_buffer = rt->hit_image = 0;
    rt->hit_size[0] = rt->hit_size[1] = 0;
}

/* --- drawing ------------------------------------------------------------- */

/* The error bound's scale (shell_frag.glsl u_err_scale) for the model
 * scale of ds: one pixel spans 2 w_clip / (proj[1][1] · height) eye units
 * at clip w. */
static double err_scale_of(const mesoi_draw* ds, const meso_rt_shell_draw* k)
{
    const double scale = ds->model_scale;
    const double error_px = k->error_px > 0.0f ? k->error_px : 1.0;
    return error_px * 2.0 / (ds->proj11 * (ds->viewport[3] > 0 ? ds->viewport[3] : 1)) / (scale > 0 ? scale : 1);
}

static meso_result instance_err(meso_rt* rt, mesoi_object* o, const mesoi_draw* ds, const meso_rt_draw_desc* d,
                                const meso_rt_instance* in, uint32_t index, float* texels, void* user)
{
    (void)rt, (void)o, (void)in, (void)index, (void)user;
    texels[35] = (float)err_scale_of(ds, &d->shell);
    return MESO_OK;
}

/* The instances' frames (has_time: their time's; else the texture shown)
 * and the order they are drawn in: grouped by frame, the texture shown
 * first (no upload), then the stored frames in ascending order, the
 * caller's order kept inside a group. groups[g] = {frame, first, count}.
 * Allocates *order and *groups (free both with mesoi_rt_free). */
typedef struct frame_group {
    uint32_t frame, first, count;
} frame_group;

static meso_result instance_frames(meso_rt* rt, const mesoi_shell* s, const meso_rt_instance* inst, uint32_t count,
                                   uint32_t** order_out, frame_group** groups_out, uint32_t* group_count)
{
    *order_out = NULL;
    *groups_out = NULL;
    *group_count = 0;
    const uint32_t frames = s->anim.frame_count, shown = s->shown_frame;
    /* key 0: the texture shown; 1 + k: stored frame k */
    uint32_t* key = mesoi_rt_alloc(rt, sizeof(uint32_t) * count);
    uint32_t* order = mesoi_rt_alloc(rt, sizeof(uint32_t) * count);
    uint32_t* first = mesoi_rt_alloc(rt, sizeof(uint32_t) * (frames + 2));
    frame_group* groups = mesoi_rt_alloc(rt, sizeof(frame_group) * (frames + 1));
    meso_result r = key && order && first && groups ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
    for (uint32_t i = 0; r == MESO_OK && i < count; ++i) {
        key[i] = 0;
        if (!frames || !inst[i].has_time)
            continue;
        if (inst[i].time != inst[i].time) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_draw_instanced: instance %u: NaN time",
                      i);
            r = MESO_ERR_INVALID_ARG;
            break;
        }
        const uint32_t k = meso_anim_frame_at(&s->anim, inst[i].time);
        key[i] = k == shown ? 0 : 1 + k;
    }
    if (r == MESO_OK) { /* a counting sort by key, stable */
        memset(first, 0, sizeof(uint32_t) * (frames + 2));
        for (uint32_t i = 0; i < count; ++i)
            ++first[key[i] + 1];
        for (uint32_t k = 0; k <= frames; ++k) {
            if (first[k + 1]) {
                groups[*group_count].frame = k == 0 ? shown : k - 1;
                groups[*group_count].first = first[k];
                groups[*group_count].count = first[k + 1];
                ++*group_count;
            }
            first[k + 1] += first[k];
        }
        for (uint32_t i = 0; i < count; ++i)
            order[first[key[i]]++] = i;
    }
    mesoi_rt_free(rt, key);
    mesoi_rt_free(rt, first);
    if (r != MESO_OK) {
        mesoi_rt_free(rt, order);
        mesoi_rt_free(rt, groups);
        return r;
    }
    *order_out = order;
    *groups_out = groups;
    return MESO_OK;
}

/* --- hull rejection (issue 14) ------------------------------------------ */
/*
 * Each layer of overlapping hulls along a pixel's ray used to ray cast,
 * the back ones too (Table 1, tests/bench/results/table1.csv: 9.1 hull
 * fragments and 96 steps per covered pixel for smooth shells before). What
 * rejects a hidden fragment before its ray cast:
 *  - not the depth test: the shaders write gl_FragDepth, and llvmpipe (Mesa
 *    22.3, lp_state_fs.c) then tests depth after the shader whatever
 *    layout(depth_greater) promises; early_fragment_tests would store the
 *    hull's depth instead of the hit's. Measured (segment only, Table 1's
 *    reference setup): with layout(depth_greater) and entry faces, a second
 *    draw of the shell over the first's depth buffer ran all 922,700
 *    fragments the first did. A GPU with conservative depth might reject in
 *    hardware; nothing here relies on it.
 *  - so the shader does: an R32UI image (rt->hit_image, image unit 0) holds
 *    per pixel the nearest depth a hit of this draw wrote (imageAtomicMin,
 *    raycast_common.glsl write_depth), cleared before the draw; the prisms
 *    rasterise their entry faces (shell_vert.glsl), so a fragment's own
 *    depth is where its ray enters, and no hit of that prism is nearer
 *    (the march starts there). A fragment whose entry is behind the stored
 *    hit by more than 64 ulps (a hit on a face two prisms share equals that
 *    face's entry up to rounding; without the margin 1 pixel in 5000 of
 *    tests/gl/test_rt_shell_reject.c changed) stops before anything else
 *    (behind_hit) and is counted as rejected, not as ray casting.
 * Why the image is unchanged: the fragment that stored d leaves the depth
 * buffer at d or nearer (it passed, or something nearer was there), and the
 * rejected fragment's hit is behind d, so it would have failed the test —
 * when the test lets the nearer win: GL_LESS/GL_LEQUAL (GL_GREATER/
 * GL_GEQUAL reversed-Z), with depth writes, which the draw turns on. The
 * function is desc->depth_func, else the host's under MESO_STATE_RESTORE,
 * else (MESO_STATE_HOST_OWNS, draw lists) taken to be the convention's
 * (meso_depth_convention says which); any other function draws without
 * rejection. Loads racing a store on a GPU only reject less.
 * Prisms containing the eye, or reaching the near plane's eye side, have
 * rays without an entry face: they draw their exit faces at the near
 * plane's depth, never rejected (shell_vert.glsl).
 * Order: rejection needs the near hits first, so the prisms are drawn
 * sorted by the mean of their six corners along the view axis in object
 * space (clip w's row of proj · view · model; orthographic: clip z's). A
 * planar depth grows along every ray, so the order depends on the axis
 * alone, not on where the eye is. The axis is snapped to the centre of its
 * cell on a cube of SORT_CELLS x SORT_CELLS cells a face (cells under 0.13
 * rad across), so a draw's order follows from its own view alone, never
 * from the draws before it; the prisms are re-sorted (on the CPU, into a
 * copy of the index buffer, order_buf) when the cell changes, after
 * meso_rt_shell_update, and on the first draw.
 * The walk (smooth shells, rt_prism_walk.c): the prisms' entry faces
 * still gave a pixel one fragment for every prism its ray crosses (9.2 a
 * covered pixel at Table 1's reference setup, 7.2 of them rejected, each
 * about 1 µs on llvmpipe: its 4x4 blocks run the shader on every lane), so
 * a side two prisms share is not drawn; the ray crossing it goes on in the
 * neighbour in the same fragment (shell_frag.glsl main), and a pixel gets a
 * fragment for each time its ray enters the shell: tests/gl/
 * test_rt_shell_reject.c measures 1.9 rasterised a covered pixel where
 * there were 7.3, the image unchanged. Prisms at the near plane keep all
 * their faces and do not walk. adj_buf holds the neighbours by slot of
 * order_buf, re-uploaded with it.
 * An instanced draw sorts for its first instance. Tetra and segment only
 * keep the mesh's order: their depths often lie on faces two neighbours
 * share (tetra's hits on the faces between tetrahedra, segment only's hull
 * exits), where both write exactly the same depth and the order drawn picks
 * which one shows; sorted, that would follow the view, and an instanced
 * draw (one order for all its instances) would no longer match separate
 * draws bit for bit (tests/gl/test_rt_instances.c; measured: 16 and 1
 * colour bytes). They reject less.
 */
#define SORT_CELLS 16

/* Whether the draw's depth test lets the nearer fragment win. */
static int nearer_wins(const mesoi_draw* ds)
{
    const GLenum f = ds->depth_func ? ds->depth_func : ds->restore ? (GLenum)ds->prev_func : mesoi_near_func(ds);
    return ds->reversed ? f == GL_GREATER || f == GL_GEQUAL : f == GL_LESS || f == GL_LEQUAL;
}

/* The direction depth grows along in object space for proj · view (pv)
 * and `model` (all zero: identity), normalised; 0 if there is none. */
static int depth_axis(const mesoi_draw* ds, const float* model, float axis[3])
{
    int identity = 1;
    for (int i = 0; i < 16; ++i)
        identity = identity && model[i] == 0.0f;
    double a[2][3], len[2] = {0, 0};
    for (int r = 0; r < 2; ++r) { /* r 0: clip w's row, 1: clip z's */
        const int row = r == 0 ? 3 : 2;
        for (int c = 0; c < 3; ++c) {
            double v = 0;
            for (int k = 0; k < 4; ++k)
                v += ds->pv[4 * k + row] * (identity ? (k == c) : model[4 * c + k]);
            a[r][c] = r == 1 && ds->reversed ? -v : v;
            len[r] += v * v;
        }
    }
    const int r = len[0] > 0.0 ? 0 : 1;
    if (!(len[r] > 0.0))
        return 0;
    for (int c = 0; c < 3; ++c)
        axis[c] = (float)(a[r][c] / sqrt(len[r]));
    return 1;
}

typedef struct prism_key {
    float key;
    uint32_t tri;
} prism_key;

static int by_key(const void* pa, const void* pb)
{
    const prism_key *a = pa, *b = pb;
    if (a->key != b->key)
        return a->key < b->key ? -1 : 1;
    return a->tri < b->tri ? -1 : a->tri > b->tri;
}

/* The cell of `a` (unit) on the cube of SORT_CELLS^2 cells a face, and
 * its centre's direction (unit). */
static int32_t axis_cell(const float a[3], float centre[3])
{
    int f = 0;
    for (int i = 1; i < 3; ++i)
        if (fabsf(a[i]) > fabsf(a[f]))
            f = i;
    const int i1 = f == 0 ? 1 : 0, i2 = f == 2 ? 1 : 2;
    int cell[2];
    double c[3], len = 0.0;
    for (int k = 0; k < 2; ++k) {
        const double t = a[k ? i2 : i1] / fabs(a[f]); /* -1..1 */
        cell[k] = (int)floor((t + 1.0) * 0.5 * SORT_CELLS);
        cell[k] = cell[k] < 0 ? 0 : cell[k] >= SORT_CELLS ? SORT_CELLS - 1 : cell[k];
        c[k ? i2 : i1] = (cell[k] + 0.5) * 2.0 / SORT_CELLS - 1.0;
    }
    c[f] = a[f] < 0 ? -1.0 : 1.0;
    for (int k = 0; k < 3; ++k)
        len += c[k] * c[k];
    for (int k = 0; k < 3; ++k)
        centre[k] = (float)(c[k] / sqrt(len));
    return ((f * 2 + (a[f] < 0)) * SORT_CELLS + cell[0]) * SORT_CELLS + cell[1];
}

/* order_buf sorted near to far along the centre of `view_axis`'s cell,
 * unless it is sorted for that cell already. */
static meso_result order_prisms(meso_rt* rt, mesoi_shell* s, const mesoi_draw* ds, const float view_axis[3])
{
    float axis[3];
    const int32_t cell = axis_cell(view_axis, axis);
    const uint64_t key = s->subset ? s->subset_key : 0;
    if (!s->order_stale && cell == s->sort_cell && key == s->sorted_key)
        return MESO_OK;
    const uint32_t n = s->subset ? s->subset_count : s->triangle_count, nv = s->vertex_count;
    prism_key* keys = mesoi_rt_alloc(rt, sizeof(prism_key) * n);
    uint32_t* sorted = mesoi_rt_alloc(rt, sizeof(uint32_t) * 3 * (size_t)n);
    int32_t* slot = mesoi_rt_alloc(rt, sizeof(int32_t) * s->triangle_count); /* triangle -> slot, -1: not drawn */
    int32_t* adj = mesoi_rt_alloc(rt, sizeof(int32_t) * 3 * (size_t)n);
    if (!keys || !sorted || !slot || !adj) {
        mesoi_rt_free(rt, keys);
        mesoi_rt_free(rt, sorted);
        mesoi_rt_free(rt, slot);
        mesoi_rt_free(rt, adj);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    uint32_t m = 0; /* prisms kept */
    for (uint32_t i = 0; i < n; ++i) {
        const uint32_t t = s->subset ? s->subset[i] : i;
        if (t >= s->triangle_count || m == s->triangle_count) /* order_buf holds each prism once */
            continue;
        double k = 0.0;
        for (int c = 0; c < 3; ++c) { /* bottom + top of each corner (fill_vertex_texels) */
            const size_t v = s->indices[3 * (size_t)t + (size_t)c];
            const float *p = s->positions + 3 * v, *d0 = s->directors + 3 * v;
            const float* d1 = s->layers == 2 ? s->directors + 3 * ((size_t)nv + v) : NULL;
            for (int j = 0; j < 3; ++j)
                k += axis[j] * (2.0 * p[j] + d0[j] + (d1 ? d1[j] : 0.0));
        }
        keys[m].key = (float)k;
        keys[m++].tri = t;
    }
    qsort(keys, m, sizeof(prism_key), by_key);
    for (uint32_t t = 0; t < s->triangle_count; ++t)
        slot[t] = -1;
    for (uint32_t t = 0; t < m; ++t) {
        memcpy(sorted + 3 * (size_t)t, s->indices + 3 * (size_t)keys[t].tri, 3 * sizeof(uint32_t));
        slot[keys[t].tri] = (int32_t)t;
    }
    for (uint32_t t = 0; t < m; ++t) /* the walk's neighbours, as slots (rt_prism_walk.c) */
        for (int k = 0; k < 3; ++k) {
            const int32_t nb = s->neighbours[3 * (size_t)keys[t].tri + (size_t)k];
            adj[3 * (size_t)t + (size_t)k] = nb >= 0 ? slot[nb] : -1;
        }
    mesoi_gl* gl = &rt->gl;
    GLint prev = 0;
    if (ds->restore)
        gl->GetIntegerv(GL_TEXTURE_BUFFER_BINDING, &prev);
    gl->BindBuffer(GL_TEXTURE_BUFFER, s->order_buf);
    gl->BufferSubData(GL_TEXTURE_BUFFER, 0, (GLsizeiptr)(sizeof(uint32_t) * 3 * (size_t)m), sorted);
    gl->BindBuffer(GL_TEXTURE_BUFFER, s->adj_buf);
    gl->BufferSubData(GL_TEXTURE_BUFFER, 0, (GLsizeiptr)(sizeof(int32_t) * 3 * (size_t)m), adj);
    if (ds->restore)
        gl->BindBuffer(GL_TEXTURE_BUFFER, (GLuint)prev);
    mesoi_rt_free(rt, keys);
    mesoi_rt_free(rt, sorted);
    mesoi_rt_free(rt, slot);
    mesoi_rt_free(rt, adj);
    s->sort_cell = cell;
    s->sorted_key = key;
    s->sorted_count = m;
    s->order_stale = 0;
    return MESO_OK;
}

/* The hit image at least the viewport's size (made with unit
 * SHELL_UNIT_HEIGHT's 2D binding, which is put back to `height_tex`), its
 * viewport part cleared to "no hit" and bound to image unit 0. */
static void hit_image_begin(meso_rt* rt, const mesoi_draw* ds, GLuint height_tex)
{
    mesoi_gl* gl = &rt->gl;
    const GLint w = ds->viewport[2], h = ds->viewport[3];
    if (w > rt->hit_size[0] || h > rt->hit_size[1]) {
        if (rt->hit_image)
            gl->DeleteTextures(1, &rt->hit_image);
        rt->hit_size[0] = w > rt->hit_size[0] ? w : rt->hit_size[0];
        rt->hit_size[1] = h > rt->hit_size[1] ? h : rt->hit_size[1];
        gl->GenTextures(1, &rt->hit_image);
        gl->ActiveTexture(GL_TEXTURE0 + SHELL_UNIT_HEIGHT);
        gl->BindTexture(GL_TEXTURE_2D, rt->hit_image);
        gl->TexStorage2D(GL_TEXTURE_2D, 1, GL_R32UI, rt->hit_size[0], rt->hit_size[1]);
        gl->BindTexture(GL_TEXTURE_2D, height_tex);
    }
    gl->MemoryBarrier(GL_TEXTURE_UPDATE_BARRIER_BIT); /* the last draw's atomics land before the clear */
    const GLuint none = 0xFFFFFFFFu;
    gl->ClearTexSubImage(rt->hit_image, 0, 0, 0, 0, w, h, 1, GL_RED_INTEGER, GL_UNSIGNED_INT, &none);
    gl->BindImageTexture(0, rt->hit_image, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
}

meso_result mesoi_shell_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                             uint32_t count)
{
    if (o->parts) /* a levelled shell's parts (rt_parts.c): prisms near, stand-in patches far */
        return mesoi_parts_draw(rt, o->parts, d, inst, count);
    const mesoi_shell* s = o->shell;
    const meso_rt_shell_draw* k = &d->shell;
    if (d->stats)
        memset(d->stats, 0, sizeof(*d->stats));
    if (k->technique == MESO_SHELL_SLICES && inst) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw_instanced: MESO_SHELL_SLICES is not instanced (its passes share one offscreen "
                  "target per draw); draw each instance with meso_rt_draw");
        return MESO_ERR_UNSUPPORTED;
    }
    if (k->technique == MESO_SHELL_SLICES)
        return mesoi_slices_draw(rt, o, d);
    if ((unsigned)k->technique >= MESO_SHELL_TECHNIQUE_COUNT) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT, "meso_rt_draw: technique %d",
                  (int)k->technique);
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_draw ds;
    meso_result r = mesoi_draw_prepare(rt, d, 1, inst != NULL, &ds);
    if (r != MESO_OK)
        return r;
    const mesoi_program* prog = shell_program(rt, k->technique, ds.stats, ds.pass);
    if (!prog)
        return MESO_ERR_GL;
    mesoi_gl* gl = &rt->gl;
    const double err_scale = err_scale_of(&ds, k);
    GLuint inst_tex = 0;
    uint32_t* order = NULL;
    frame_group* groups = NULL;
    uint32_t group_count = 0;
    if (inst) {
        r = instance_frames(rt, s, inst, count, &order, &groups, &group_count);
        if (r == MESO_OK)
            r = mesoi_instances_upload(rt, &ds, o, d, inst, order, count, 1, instance_err, NULL, &inst_tex);
        if (r != MESO_OK) {
            mesoi_rt_free(rt, order);
            mesoi_rt_free(rt, groups);
            return r;
        }
    }
    float max_tex = fmaxf(s->tex_size[0], fmaxf(s->tex_size[1], s->tex_size[2]));

    static const GLenum unit_target[SHELL_UNITS_ALL] = {GL_TEXTURE_BUFFER, GL_TEXTURE_BUFFER, GL_TEXTURE_2D,
                                                        GL_TEXTURE_3D,     GL_TEXTURE_3D,     GL_TEXTURE_3D,
                                                        GL_TEXTURE_BUFFER, GL_TEXTURE_BUFFER};
    const GLuint bind[SHELL_UNITS_ALL] = {s->vert_tex, s->index_tex, s->tex_kind == 1 ? s->func_tex : 0,
                                          s->tex_kind == 2 ? s->func_tex : 0, s->dist_tex, s->color_tex, inst_tex,
                                          s->adj_tex};
    mesoi_draw_begin(rt, &ds, prog, 1, SHELL_UNITS_ALL, unit_target, bind);
    const GLint* u = prog->loc;
    float axis[3] = {0.0f, 0.0f, 1.0f};
    const int reject = rt->hull_reject_ok && !k->no_hull_reject && ds.viewport[2] > 0 && ds.viewport[3] > 0 &&
                       nearer_wins(&ds) && depth_axis(&ds, inst ? inst[0].model : ds.model, axis);
    /* The walk (rt_prism_walk.c): smooth shells, with rejection (it draws
     * the entry faces the walk leaves out of the shared sides). */
    const int walk = reject && k->technique == MESO_SHELL_SMOOTH && !k->no_prism_walk && s->adj_tex;
    mesoi_image_unit prev_image;
    if (reject && ds.restore)
        mesoi_image_save(rt, &prev_image);
    /* A subset of the prisms (a parts draw) is drawn from order_buf too,
     * sorted as the whole set is (the parts pick only asks where there is
     * an order_buf). */
    if ((reject && (k->technique == MESO_SHELL_SMOOTH || k->technique == MESO_SHELL_CURVED)) ||
        (s->subset && s->order_tex)) {
        if (!reject)
            depth_axis(&ds, inst ? inst[0].model : ds.model, axis);
        r = order_prisms(rt, o->shell, &ds, axis);
        gl->ActiveTexture(GL_TEXTURE0 + SHELL_UNIT_INDEX);
        gl->BindTexture(GL_TEXTURE_BUFFER, s->order_tex);
    }
    if (reject)
        hit_image_begin(rt, &ds, bind[SHELL_UNIT_HEIGHT]);
    gl->Uniform1i(u[MESOI_U_hull_reject], reject);
    gl->Uniform1i(u[MESOI_U_walk], walk);
    /* No prism reaches the near plane (the usual case; instanced: of any
     * instance): the vertex shader skips the test per prism and per
     * neighbour. */
    int near = 0;
    for (uint32_t i = 0; i < (inst ? count : 1) && !near; ++i)
        near = box_reaches_near(&ds, inst ? inst[i].model : ds.model, s->box_min, s->box_max);
    gl->Uniform1i(u[MESOI_U_near], near);
    /* The bottom caps left out (rt_prism_walk.c): a closed shell solid at
     * w = 0, its box wholly beyond the near plane. */
    gl->Uniform1i(u[MESOI_U_no_bottom], walk && !near && s->closed && s->tex_kind != 2);
    gl->Uniform1f(u[MESOI_U_uv_scale], k->uv_scale > 0.0f ? k->uv_scale : 1.0f);
    gl->Uniform1i(u[MESOI_U_tex_kind], s->tex_kind);
    gl->Uniform1i(u[MESOI_U_has_color], s->color_tex != 0);
    gl->Uniform3fv(u[MESOI_U_color_scale], 1, s->color_scale);
    gl->Uniform1i(u[MESOI_U_has_dist], s->dist_tex && !k->no_distance_map);
    gl->Uniform3fv(u[MESOI_U_tex_size], 1, s->tex_size);
    gl->Uniform1f(u[MESOI_U_err_scale], (float)err_scale);
    gl->Uniform1i(u[MESOI_U_max_steps], k->max_steps > 0 ? k->max_steps : 256);
    gl->Uniform1i(u[MESOI_U_bisect_steps], k->bisection_steps > 0 ? k->bisection_steps : 4);
    gl->Uniform1i(u[MESOI_U_segment_steps], k->segment_steps > 0 ? k->segment_steps : 12);
    gl->Uniform1f(u[MESOI_U_fixed_step], k->fixed_step > 0.0f ? k->fixed_step : 1.0f / 256);
    /* Where the distance map says 0 (a cell touching the solid), step a
     * quarter texel: finer than the texture's own detail. */
    gl->Uniform1f(u[MESOI_U_min_step], max_tex > 1.0f ? 0.25f / max_tex : 1.0f / 1024);
    const GLsizei per = k->technique == MESO_SHELL_TETRA ? 36 : 24;
    const GLsizei prisms = (GLsizei)(s->subset && s->order_tex ? s->sorted_count : s->triangle_count);
    if (!inst) {
        if (r == MESO_OK)
            gl->DrawArrays(GL_TRIANGLES, 0, per * prisms);
        const meso_result e = mesoi_draw_end(rt, &ds, d->stats, "shell");
        if (reject && ds.restore)
            mesoi_image_restore(rt, &prev_image);
        return r != MESO_OK ? r : e;
    }
    /* One instanced call per frame the instances show (one in all when
     * the object has no stored frames or they show one). */
    for (uint32_t g = 0; g < group_count && r == MESO_OK; ++g) {
        if (groups[g].frame != s->shown_frame) {
            r = show_frame(rt, o->shell, groups[g].frame, "meso_rt_draw_instanced");
            const GLuint now[3] = {s->tex_kind == 1 ? s->func_tex : 0, s->tex_kind == 2 ? s->func_tex : 0,
                                   s->dist_tex};
            for (int unit = 0; unit < 3; ++unit) {
                gl->ActiveTexture(GL_TEXTURE0 + SHELL_UNIT_HEIGHT + (GLenum)unit);
                gl->BindTexture(unit_target[SHELL_UNIT_HEIGHT + unit], now[unit]);
            }
        }
        gl->Uniform1i(u[MESOI_U_instance_base], (GLint)groups[g].first);
        if (r == MESO_OK)
            gl->DrawArraysInstanced(GL_TRIANGLES, 0, per * prisms, (GLsizei)groups[g].count);
    }
    mesoi_rt_free(rt, order);
    mesoi_rt_free(rt, groups);
    const meso_result e = mesoi_draw_end(rt, &ds, d->stats, "shell");
    if (reject && ds.restore)
        mesoi_image_restore(rt, &prev_image);
    return r != MESO_OK ? r : e;
}
