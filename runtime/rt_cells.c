/*
 * rt_cells.c — CELLS objects (FORMAT.md §7.2 kind 3, §7.8): streaming one
 * object's MESH, CELL, TILE, MEMB, NRMM and COLR chunks into GL and ray
 * tracing its cells (papers/cell-based-object-representation.md §3.2; the
 * shaders are runtime/shaders/cells_*.glsl, the rules and the reference
 * they are measured against runtime/reference/cell_reference.h).
 *
 * GL layout, everything as stored (no re-encoding):
 *   unit 0  TILE  3D texture R16UI / R32UI, R^3 (nearest); the split ids as
 *                 stored, with each voxel's skip radius packed above them
 *                 where they leave room (rt_cells_skip.c)
 *   unit 1  MEMB  texture buffer R32UI over the sparse words (classes, rank,
 *                 records: the shader finds a MIXED tile's record with the
 *                 rank word plus a popcount, as FORMAT.md describes)
 *   unit 2  NRMM  3D texture RG16 (unorm; RG32F of the same values on ES
 *                 without GL_EXT_texture_norm16), decoded in the shader
 *   unit 3  COLR  3D texture SRGB8_ALPHA8 (fetches are linear)
 *   unit 4  the host's environment cube map, if it passes one
 *   unit 5  TX3D, the mesh's colour grid when the object has one: 3D texture
 *           SRGB8_ALPHA8, interpolated by hand (trilinear, float weights)
 * plus the base mesh's vertex array (the MESH chunk buffer, as rt_mesh.c
 * uploads it). SPLT is not needed to draw: MEMB's tags are final.
 *
 * Decisions:
 *  - Rays start where the pixel ray meets a front face of the base mesh
 *    (§3.2.1). When the camera's near plane reaches into the tile grid,
 *    back faces are drawn too and start at the near plane (or the grid's
 *    entry), so the camera may be inside the object.
 *  - The thesis discards a ray that meets an OUTSIDE cell (§3.2.2, Figure
 *    3.13) because a later base-mesh entry takes over. That is not exact: an
 *    OUTSIDE cell's voxel cubes reach up to half a voxel diagonal into the
 *    mesh, and a ray there may still reach INSIDE cells with no further
 *    entry. meso walks on instead; OUTSIDE tiles are crossed in one step,
 *    so what it costs is the walk through the intersected band.
 *  - Inside a MIXED tile the walk leaves, in one step, the largest cube
 *    around its voxel that holds one split cell (rt_cells_skip.c): the
 *    answer is the voxel walk's, the steps fewer.
 *  - The file is checked as meso_file_check_cells does before anything is
 *    uploaded, so the shaders never index past their data; TILE and MEMB
 *    are uploaded from the check's own copies (read once).
 */
#include "file_internal.h"
#include "mat4_inverse.h"
#include "rt_cells_skip.h"
#include "rt_internal.h"
#include "shaders_embedded.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

typedef struct mesoi_cells {
    uint32_t tiles[3], res, split_count;
    uint32_t class_words, record_words; /* ceil(T / 16), W */
    float origin[3], voxel;
    int map_full;
    int id_bits; /* TILE's values: split id in the low id_bits, skip radius above; 0 ids only */
    GLuint tile_tex, memb_buf, memb_tex, nrmm_tex, colr_tex, grid_tex;
    GLint grid[3]; /* TX3D colour grid dims; 0 without one */
} mesoi_cells;

enum { UNIT_TILE = 0, UNIT_MEMB, UNIT_NRMM, UNIT_COLR, UNIT_ENV, UNIT_GRID, UNIT_COUNT };

void mesoi_cells_release(meso_rt* rt, mesoi_object* o)
{
    mesoi_cells* c = o->cells;
    if (!c)
        return;
    mesoi_gl* gl = &rt->gl;
    const GLuint tex[5] = {c->tile_tex, c->memb_tex, c->nrmm_tex, c->colr_tex, c->grid_tex};
    gl->DeleteTextures(5, tex);
    gl->DeleteBuffers(1, &c->memb_buf);
    mesoi_rt_free(rt, c);
    o->cells = NULL;
}

/* A 3D texture from a chunk's payload, nearest, clamped. */
static meso_result upload_3d(meso_rt* rt, const meso_chunk_info* c, const void* data, GLint internal,
                             GLenum format, GLenum type, GLuint* out)
{
    mesoi_gl* gl = &rt->gl;
    /* Refused before GL sees it, so the host's error queue stays its own. */
    GLint limit = 0;
    gl->GetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &limit);
    for (int k = 0; k < 3; ++k)
        if (c->dims[k] == 0 || c->dims[k] > (uint32_t)limit) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR,
                      "cells: a %ux%ux%u texture exceeds this context's limit of %d texels a side", c->dims[0],
                      c->dims[1], c->dims[2], (int)limit);
            *out = 0;
            return MESO_ERR_GL;
        }
    GLint prev_tex = 0;
    gl->GetIntegerv(GL_TEXTURE_BINDING_3D, &prev_tex);
    mesoi_unpack unpack;
    mesoi_unpack_default(rt, &unpack);
    gl->GenTextures(1, out);
    gl->BindTexture(GL_TEXTURE_3D, *out);
    gl->TexImage3D(GL_TEXTURE_3D, 0, internal, (GLsizei)c->dims[0], (GLsizei)c->dims[1], (GLsizei)c->dims[2], 0,
                   format, type, rt->defer ? NULL : data); /* deferred: the data later (rt_transfer.c) */
    gl->TexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl->TexParameteri(GL_TEXTURE_3D, GL_TEXTURE_MAX_LEVEL, 0);
    GLint width = 0; /* no level 0: GL refused it (the error queue stays the host's) */
    gl->GetTexLevelParameteriv(GL_TEXTURE_3D, 0, GL_TEXTURE_WIDTH, &width);
    gl->BindTexture(GL_TEXTURE_3D, (GLuint)prev_tex);
    mesoi_unpack_restore(rt, &unpack);
    if (width != (GLint)c->dims[0]) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "cells: a %ux%ux%u texture could not be created",
                  c->dims[0], c->dims[1], c->dims[2]);
        gl->DeleteTextures(1, out);
        *out = 0;
        return MESO_ERR_GL;
    }
    rt->gpu_count += (uint64_t)c->dims[0] * c->dims[1] * c->dims[2] * mesoi_internal_bytes(internal);
    if (rt->defer) {
        int components = 1;
        mesoi_defer_texture(rt, *out, GL_TEXTURE_3D, 0, c->dims, format, type,
                            mesoi_texel_bytes(format, type, &components), 0, data);
    }
    return MESO_OK;
}

/* Reads a whole chunk and uploads it as a 3D texture. */
static meso_result upload_chunk_3d(meso_rt* rt, meso_file* f, int32_t ci, GLint internal, GLenum format, GLenum type,
                                   GLuint* out)
{
    void* data = NULL;
    size_t size = 0;
    meso_result r = mesoi_read_whole(rt, f, ci, &data, &size);
    if (r == MESO_OK && internal == GL_RG16 && !rt->norm16) {
        /* ES without GL_EXT_texture_norm16: the same values as RG32F (exact;
         * fetched nearest, so no filtering needed). */
        float* conv = mesoi_unorm16_to_float(rt, data, size / 2);
        mesoi_rt_free(rt, data);
        data = conv;
        r = conv ? MESO_OK : MESO_ERR_OUT_OF_MEMORY;
        internal = GL_RG32F;
        type = GL_FLOAT;
    }
    if (r == MESO_OK)
        r = upload_3d(rt, meso_file_chunk(f, (uint32_t)ci), data, internal, format, type, out);
    mesoi_rt_free(rt, data);
    return r;
}

static meso_result read_grid(meso_rt* rt, meso_file* f, uint32_t id, int32_t ci, mesoi_cells* c)
{
    uint8_t rec[MESO_CELL_RECORD_SIZE];
    void* data = NULL;
    size_t size = 0;
    meso_result r = mesoi_read_whole(rt, f, ci, &data, &size); /* streamed: handed over (rt_stream.c) */
    if (r == MESO_OK && size != sizeof rec) { /* the cells check refuses it first (6301..) */
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "cells %u: CELL has %zu bytes, not %zu", id,
                  size, sizeof rec);
        r = MESO_ERR_CORRUPT;
    }
    if (r == MESO_OK)
        memcpy(rec, data, sizeof rec);
    mesoi_rt_free(rt, data);
    if (r != MESO_OK)
        return r;
    uint64_t T = 1;
    for (int a = 0; a < 3; ++a) {
        c->tiles[a] = mesoi_ld32(rec + MESO_CELL_OFF_TILES + 4 * a);
        c->origin[a] = mesoi_ldf32(rec + MESO_CELL_OFF_ORIGIN + 4 * a);
        T *= c->tiles[a];
    }
    c->res = mesoi_ld32(rec + MESO_CELL_OFF_TILE_RES);
    c->split_count = mesoi_ld32(rec + MESO_CELL_OFF_SPLIT_COUNT);
    c->voxel = mesoi_ldf32(rec + MESO_CELL_OFF_VOXEL_SIZE);
    c->class_words = (uint32_t)((T + 15) / 16);
    c->record_words = (uint32_t)((2ull * c->split_count + 31) / 32);
    /* The shader indexes with 32-bit ints: voxels per axis, tiles and words. */
    const uint64_t words = 2ull * c->class_words + mesoi_ld64(rec + MESO_CELL_OFF_MIXED_TILES) * c->record_words;
    GLint max_buf = 0, max_3d = 0;
    rt->gl.GetIntegerv(GL_MAX_TEXTURE_BUFFER_SIZE, &max_buf);
    rt->gl.GetIntegerv(GL_MAX_3D_TEXTURE_SIZE, &max_3d);
    for (int a = 0; a < 3; ++a)
        if ((uint64_t)c->tiles[a] * c->res > (uint64_t)INT32_MAX)
            T = UINT64_MAX;
    if (T > (uint64_t)INT32_MAX || words > (uint64_t)max_buf || c->res > (uint32_t)max_3d) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                  "cells %u: %u x %u x %u tiles of %u^3 voxels with %llu MEMB words exceed this context (texture "
                  "buffer %d texels, 3D textures %d)",
                  id, c->tiles[0], c->tiles[1], c->tiles[2], c->res, (unsigned long long)words, max_buf, max_3d);
        return MESO_ERR_UNSUPPORTED;
    }
    return MESO_OK;
}

meso_result mesoi_cells_load(meso_rt* rt, meso_file* f, uint32_t id, mesoi_object* o)
{
    /* The check reads TILE and MEMB anyway; they are uploaded from its copies. */
    uint8_t *tile = NULL, *memb = NULL;
    meso_error err;
    int id_bits = 0;
    const int streamed = mesoi_stream_take_cells(rt, &tile, &memb, &id_bits); /* checked off the GL thread */
    meso_result r = streamed ? MESO_OK : mesoi_file_check_cells_keep(f, id, rt->load_lod, &tile, &memb, &err);
    if (r != MESO_OK) {
        if (r != MESO_ERR_PENDING) /* not arrived yet is not an error */
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "cells %u: %s", id, err.message);
        return r;
    }
    static const uint32_t types[5] = {MESO_CHUNK_CELL, MESO_CHUNK_TILE, MESO_CHUNK_MEMB, MESO_CHUNK_NRMM,
                                      MESO_CHUNK_COLR};
    int32_t ci[5];
    for (int k = 0; k < 5; ++k)
        ci[k] = mesoi_find_chunk(rt, f, types[k], id); /* present: checked above */
    mesoi_cells* c = mesoi_rt_alloc(rt, sizeof(*c));
    if (!c) {
        mesoi_file_free(&f->alloc, tile);
        mesoi_file_free(&f->alloc, memb);
        return MESO_ERR_OUT_OF_MEMORY;
    }
    memset(c, 0, sizeof(*c));
    o->cells = c;
    r = read_grid(rt, f, id, ci[0], c);
    if (r == MESO_OK)
        r = mesoi_mesh_upload(rt, f, id, 0, o);
    const GLint prev_tex_buffer = mesoi_upload_begin(rt);
    if (r == MESO_OK) {
        const meso_chunk_info* tc = meso_file_chunk(f, (uint32_t)ci[1]);
        const int wide = tc->dtype == MESO_DTYPE_U32;
        const size_t n = (size_t)tc->dims[0] * tc->dims[1] * tc->dims[2];
        c->id_bits = streamed ? id_bits : mesoi_cells_skip_level(f, id, rt->load_lod, tile, &rt->alloc);
        const uint32_t ids = c->id_bits ? (1u << c->id_bits) - 1u : UINT32_MAX; /* the radii above them */
        c->map_full = 1; /* is there empty space in the map? */
        for (size_t v = 0; v < n && c->map_full; ++v)
            c->map_full = ((wide ? mesoi_ld32(tile + 4 * v) : mesoi_ld16(tile + 2 * v)) & ids) != 0;
        r = upload_3d(rt, tc, tile, wide ? GL_R32UI : GL_R16UI, GL_RED_INTEGER,
                      wide ? GL_UNSIGNED_INT : GL_UNSIGNED_SHORT, &c->tile_tex);
        if (r == MESO_OK) {
            c->memb_tex = mesoi_texture_buffer(rt, GL_R32UI, memb,
                                               (size_t)meso_file_chunk(f, (uint32_t)ci[2])->decoded_size, &c->memb_buf);
            r = c->memb_tex ? MESO_OK : MESO_ERR_GL;
        }
        if (r == MESO_OK)
            r = upload_chunk_3d(rt, f, ci[3], GL_RG16, GL_RG, GL_UNSIGNED_SHORT, &c->nrmm_tex);
    }
    if (r == MESO_OK)
        r = upload_chunk_3d(rt, f, ci[4], GL_SRGB8_ALPHA8, GL_RGBA, GL_UNSIGNED_BYTE, &c->colr_tex);
    const int32_t gi = mesoi_find_chunk(rt, f, MESO_CHUNK_TX3D, id); /* the mesh's colour grid */
    if (r == MESO_OK && gi >= 0) {
        const meso_chunk_info* gc = meso_file_chunk(f, (uint32_t)gi);
        if (gc->dtype != MESO_DTYPE_U8 || gc->components != 4) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "cells %u: TX3D is dtype %u x %u; FORMAT.md §7.2 wants U8 x 4 (the colour grid)", id,
                      gc->dtype, gc->components);
            r = MESO_ERR_UNSUPPORTED;
        } else {
            r = upload_chunk_3d(rt, f, gi, GL_SRGB8_ALPHA8, GL_RGBA, GL_UNSIGNED_BYTE, &c->grid_tex);
            for (int k = 0; k < 3; ++k)
                c->grid[k] = (GLint)gc->dims[k];
        }
    }
    mesoi_file_free(&f->alloc, tile);
    mesoi_file_free(&f->alloc, memb);
    char what[48];
    snprintf(what, sizeof(what), "uploading cells %u", id);
    r = mesoi_upload_end(rt, prev_tex_buffer, r, what);
    if (r != MESO_OK) {
        mesoi_cells_release(rt, o);
        rt->gl.DeleteVertexArrays(1, &o->vao);
        rt->gl.DeleteBuffers(1, &o->buffer);
        o->vao = o->buffer = 0;
    }
    return r;
}

/* >>drawing ---------------------------------------------------------------- */

static const mesoi_program* cells_program(meso_rt* rt, int stats, meso_rt_pass pass)
{
    mesoi_program* p = &rt->cells_programs[pass][stats];
    if (p->id)
        return p;
    char head[512];
    snprintf(head, sizeof(head), "%s#define MESO_INSTANCE_MODEL 1\n", mesoi_glsl_prelude(rt, stats));
    const char* vs[4] = {head, MESOI_GLSL_VERTEX_STAGE, mesoi_glsl_instance, mesoi_glsl_cells_vert};
    const char* pre[2] = {mesoi_glsl_instance, mesoi_glsl_raycast_common};
    static const char* const samplers[UNIT_COUNT + 1] = {"u_tile", "u_memb", "u_nrmm", "u_colr", "u_env",
                                                         "u_grid", "u_instances"};
    static const char* const names[MESO_PASS_COUNT] = {"cells", "cells depth", "cells gbuffer"};
    const mesoi_program_src src = {.vs = vs, .vs_count = 4, .vs_file = "cells_vert.glsl", .pre = pre,
                                   .pre_count = 2, .frag = mesoi_glsl_cells_frag, .frag_file = "cells_frag.glsl",
                                   .name = names[pass], .samplers = samplers, .sampler_count = UNIT_COUNT + 1};
    return mesoi_program_build(rt, p, pass, &src);
}

meso_result mesoi_cells_prepare(meso_rt* rt, int stats, meso_rt_pass pass)
{
    return cells_program(rt, stats, pass) ? MESO_OK : MESO_ERR_GL;
}

void mesoi_cells_programs_destroy(meso_rt* rt)
{
    for (int pass = 0; pass < MESO_PASS_COUNT; ++pass)
        for (int st = 0; st < 2; ++st)
            mesoi_program_delete(rt, &rt->cells_programs[pass][st]);
}

/* 1 when the near plane may reach into the grid box (its rectangle's
 * bounding box in object space overlaps the grid's, and some corner of the
 * grid is not beyond the near plane): then rays must also start at the
 * near plane. */
static int near_plane_in_grid(const mesoi_draw* ds, const mesoi_cells* c)
{
    double inv[16], lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < 16; ++i)
        inv[i] = ds->inv_mvp[i];
    for (int k = 0; k < 4; ++k) {
        const double ndc[4] = {k & 1 ? 1.0 : -1.0, k & 2 ? 1.0 : -1.0, ds->depth_ndc[0], 1.0};
        double p[4] = {0, 0, 0, 0};
        for (int row = 0; row < 4; ++row)
            for (int col = 0; col < 4; ++col)
                p[row] += inv[4 * col + row] * ndc[col];
        for (int a = 0; a < 3; ++a) {
            lo[a] = fmin(lo[a], p[a] / p[3]);
            hi[a] = fmax(hi[a], p[a] / p[3]);
        }
    }
    double g0[3], g1[3];
    for (int a = 0; a < 3; ++a) {
        g0[a] = c->origin[a];
        g1[a] = c->origin[a] + (double)c->tiles[a] * c->res * c->voxel;
        if (hi[a] < g0[a] || lo[a] > g1[a])
            return 0;
    }
    /* The rectangle's box is loose for a tilted view: it may overlap the
     * grid while the whole grid lies beyond the near plane, and back faces
     * drawn then tie in depth with the front faces' hits. So also: some
     * corner of the grid on the eye's side of the near plane (or behind the
     * eye). The grid is convex: with none, no ray starts inside it. */
    const double n0 = ds->depth_ndc[0], towards_far = ds->depth_ndc[1] - ds->depth_ndc[0];
    for (int k = 0; k < 8; ++k) {
        const double q[4] = {k & 1 ? g1[0] : g0[0], k & 2 ? g1[1] : g0[1], k & 4 ? g1[2] : g0[2], 1.0};
        double z = 0.0, w = 0.0;
        for (int col = 0; col < 4; ++col) {
            z += (double)ds->mvp[4 * col + 2] * q[col];
            w += (double)ds->mvp[4 * col + 3] * q[col];
        }
        if (!(w > 0.0) || (z / w - n0) * towards_far <= 0.0)
            return 1;
    }
    return 0;
}

/* The model's rotation, object -> world directions (u_env_rot). */
static void env_rotation(const mesoi_draw* ds, float rot[9])
{
    for (int col = 0; col < 3; ++col)
        for (int row = 0; row < 3; ++row)
            rot[3 * col + row] = (float)(ds->model[4 * col + row] / ds->model_scale);
}

/* Whether an instance's rays start at the near plane (ORed into *user);
 * its rotation is its model's (texels 10-13) over the scale
 * (instance.glsl). */
static meso_result instance_cells(meso_rt* rt, mesoi_object* o, const mesoi_draw* ds, const meso_rt_draw_desc* d,
                                  const meso_rt_instance* in, uint32_t index, float* texels, void* user)
{
    (void)rt, (void)d, (void)in, (void)index, (void)texels;
    *(int*)user |= near_plane_in_grid(ds, o->cells);
    return MESO_OK;
}

meso_result mesoi_cells_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                             uint32_t count)
{
    const mesoi_cells* c = o->cells;
    const meso_rt_cells_draw* k = &d->cells;
    if (k->mode < MESO_CELLS_FIRST_HIT || k->mode > MESO_CELLS_REFRACT || k->bounces < 0 ||
        k->bounces > 8 || !(k->step >= 0.0f) || k->ior < 0.0f || k->reflectivity < 0.0f ||
        k->reflectivity > 1.0f || k->transparency < 0.0f || k->transparency > 1.0f || k->footprint_rays < 0 ||
        k->footprint_rays > 4) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw: cells knobs out of range (mode %d, bounces %d of 0..8, step %g, ior %g, "
                  "reflectivity %g and transparency %g of 0..1, footprint_rays %d of 0..4)",
                  (int)k->mode, k->bounces, (double)k->step, (double)k->ior,
                  (double)k->reflectivity, (double)k->transparency, k->footprint_rays);
        return MESO_ERR_INVALID_ARG;
    }
    mesoi_draw ds;
    meso_result r = mesoi_draw_prepare(rt, d, 1, inst != NULL, &ds);
    if (r != MESO_OK)
        return r;
    const mesoi_program* prog = cells_program(rt, ds.stats, ds.pass);
    if (!prog)
        return MESO_ERR_GL;
    mesoi_gl* gl = &rt->gl;
    static const GLenum targets[UNIT_COUNT + 1] = {GL_TEXTURE_3D, GL_TEXTURE_BUFFER, GL_TEXTURE_3D, GL_TEXTURE_3D,
                                                   GL_TEXTURE_CUBE_MAP, GL_TEXTURE_3D, GL_TEXTURE_BUFFER};
    GLuint bind[UNIT_COUNT + 1] = {c->tile_tex, c->memb_tex, c->nrmm_tex, c->colr_tex, k->environment, c->grid_tex,
                                   0};
    int from_near = 0;
    if (inst && (r = mesoi_instances_upload(rt, &ds, o, d, inst, NULL, count, 1, instance_cells, &from_near,
                                            &bind[UNIT_COUNT])) != MESO_OK)
        return r;
    mesoi_draw_begin(rt, &ds, prog, 1, inst ? UNIT_COUNT + 1 : UNIT_COUNT, targets, bind);
    if (!inst)
        from_near = near_plane_in_grid(&ds, c);
    if (from_near)
        gl->Disable(GL_CULL_FACE);
    else
        gl->CullFace(GL_BACK);
    gl->BindVertexArray(o->vao);
    const GLint* u = prog->loc;
    gl->Uniform1i(u[MESOI_U_has_env], k->environment != 0);
    float rot[9];
    env_rotation(&ds, rot);
    gl->UniformMatrix3fv(u[MESOI_U_env_rot], 1, GL_FALSE, rot);
    gl->Uniform3fv(u[MESOI_U_origin], 1, c->origin);
    gl->Uniform1f(u[MESOI_U_h], c->voxel);
    gl->Uniform3i(u[MESOI_U_tiles], (GLint)c->tiles[0], (GLint)c->tiles[1], (GLint)c->tiles[2]);
    gl->Uniform1i(u[MESOI_U_res], (GLint)c->res);
    gl->Uniform3i(u[MESOI_U_grid_size], c->grid[0], c->grid[1], c->grid[2]);
    gl->Uniform1i(u[MESOI_U_class_words], (GLint)c->class_words);
    gl->Uniform1i(u[MESOI_U_words], (GLint)c->record_words);
    gl->Uniform1i(u[MESOI_U_map_full], c->map_full);
    gl->Uniform1i(u[MESOI_U_id_bits], c->id_bits);
    gl->Uniform1i(u[MESOI_U_from_near], from_near);
    gl->Uniform1i(u[MESOI_U_mode], (GLint)k->mode);
    gl->Uniform1i(u[MESOI_U_bounces], k->bounces);
    gl->Uniform1f(u[MESOI_U_refl], k->reflectivity > 0.0f ? k->reflectivity : 0.5f);
    gl->Uniform1f(u[MESOI_U_ior], k->ior > 0.0f ? k->ior : 1.5f);
    gl->Uniform1f(u[MESOI_U_tau], k->transparency > 0.0f ? k->transparency : 0.7f);
    gl->Uniform1f(u[MESOI_U_step], k->step);
    gl->Uniform1i(u[MESOI_U_fixed_step], k->fixed_step != 0);
    int bisect = k->bisection_steps;
    if (bisect <= 0) /* down to 1/64 voxel */
        bisect = k->step > 0.0f ? (int)ceil(log2((double)k->step * 64.0)) : 0;
    gl->Uniform1i(u[MESOI_U_bisect], bisect > 0 ? bisect : 1);
    gl->Uniform1i(u[MESOI_U_max_steps], k->max_steps > 0 ? k->max_steps : 4096);
    gl->Uniform1i(u[MESOI_U_footprint_rays], k->footprint_rays);
    if (inst)
        gl->DrawElementsInstanced(GL_TRIANGLES, o->index_count, o->index_type,
                                  (const void*)(uintptr_t)o->indices_offset, (GLsizei)count);
    else
        gl->DrawElements(GL_TRIANGLES, o->index_count, o->index_type, (const void*)(uintptr_t)o->indices_offset);
    return mesoi_draw_end(rt, &ds, d->stats, "cells");
}
