/*
 * rt_mesh.c — the MESH kind: stream an object's MESH chunk into one GL
 * buffer and draw it as the shaded base mesh (two-sided Lambert,
 * shaders/mesh_*.glsl), through the same state save/restore as every kind
 * (mesoi_draw_begin / mesoi_draw_end, rt_common.c).
 *
 * The decoded MESH chunk goes up repacked for the GPU (rt_mesh_repack.c:
 * positions, 10-bit normals, 16-bit indices where they fit, no uvs; a
 * streamed level's repacked off the GL thread, with its decode), one
 * buffer serving as vertex and index buffer. A stand-in
 * level's vertex colours (VCOL: sRGB albedo and occlusion per vertex, or
 * the occlusion alone, the appearance the baker averaged over each
 * vertex's part of the finer surface) follow the mesh in the same buffer;
 * without them the mesh is drawn with the draw's albedo, not darkened.
 */
#include "rt_internal.h"
#include "shaders_embedded.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* The mesh program of `pass` (built on first use). */
static const mesoi_program* mesh_program(meso_rt* rt, meso_rt_pass pass)
{
    mesoi_program* p = &rt->mesh_programs[pass];
    if (p->id)
        return p;
    char head[512];
    snprintf(head, sizeof(head), "%s#define MESO_INSTANCE_MODEL 1\n", mesoi_glsl_prelude(rt, 0));
    const char* vs[4] = {head, MESOI_GLSL_VERTEX_STAGE, mesoi_glsl_instance, mesoi_glsl_mesh_vert};
    const char* pre[2] = {mesoi_glsl_instance, mesoi_glsl_raycast_common};
    static const char* const names[MESO_PASS_COUNT] = {"mesh", "mesh depth", "mesh gbuffer"};
    static const char* const samplers[1] = {"u_instances"}; /* unit 0: the instance data */
    const mesoi_program_src src = {.vs = vs, .vs_count = 4, .vs_file = "mesh_vert.glsl", .pre = pre, .pre_count = 2,
                                   .frag = mesoi_glsl_mesh_frag, .frag_file = "mesh_frag.glsl", .name = names[pass],
                                   .samplers = samplers, .sampler_count = 1};
    return mesoi_program_build(rt, p, pass, &src);
}

meso_result mesoi_mesh_prepare(meso_rt* rt, meso_rt_pass pass)
{
    return mesh_program(rt, pass) ? MESO_OK : MESO_ERR_GL;
}

meso_result mesoi_mesh_upload(meso_rt* rt, meso_file* f, uint32_t object_id, int colours, mesoi_object* o)
{
    const int32_t ci = mesoi_find_chunk(rt, f, MESO_CHUNK_MESH, object_id);
    if (ci < 0) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_OBJECT_NOT_FOUND, "object %u has no MESH chunk", object_id);
        return MESO_ERR_NOT_FOUND;
    }
    return mesoi_mesh_upload_chunk(rt, f, ci, object_id, colours ? meso_file_find_vertex_colours(f, object_id, rt->load_lod) : -1,
                                   o);
}

meso_result mesoi_mesh_upload_chunk(meso_rt* rt, meso_file* f, int32_t ci, uint32_t object_id, int32_t vi,
                                    mesoi_object* o)
{
    /* Streamed: parsed and repacked with the level's decode (rt_stream.c);
     * else read and repacked here. */
    mesoi_mesh_gpu mg;
    void* data = mesoi_stream_take_mesh(rt, ci, &mg);
    meso_result r = MESO_OK;
    if (!data) {
        size_t read = 0;
        if ((r = mesoi_read_whole(rt, f, ci, &data, &read)) != MESO_OK)
            return r;
        meso_error err;
        if ((r = mesoi_mesh_repack(data, read, &mg, &err)) != MESO_OK) {
            mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_CHUNK_READ_FAILED, "object %u: %s", object_id, err.message);
            mesoi_rt_free(rt, data);
            return r;
        }
    }
    const size_t size = mg.bytes;
    /* The vertex colours (FORMAT.md 7.3 VCOL) go into the same buffer,
     * after the mesh at the next multiple of 16. One that does not fit the
     * mesh (a file not validated in full) is not drawn, and said. */
    void* vcol = NULL;
    size_t vcol_size = 0;
    if (vi >= 0) {
        const meso_chunk_info* vc = meso_file_chunk(f, (uint32_t)vi);
        const int fits = (vc->components == 4 || vc->components == 1) &&
                         (vc->type == MESO_CHUNK_PVCL /* a part's (§7.11): BYTES, dims[0] the part */
                              ? vc->dtype == MESO_DTYPE_BYTES &&
                                    vc->decoded_size == (uint64_t)mg.vertex_count * vc->components
                              : vc->dtype == MESO_DTYPE_U8 && vc->dims[0] == mg.vertex_count &&
                                    vc->dims[1] == 1 && vc->dims[2] == 1);
        if (!fits) {
            mesoi_log(rt, MESO_LOG_WARNING, MESO_LOGITEM_CHUNK_READ_FAILED,
                      "object %u: VCOL (chunk %d) is not U8 x 4 or x 1 for each of the MESH's %u vertices; drawn "
                      "without it",
                      object_id, (int)vi, mg.vertex_count);
        } else if ((r = mesoi_read_whole(rt, f, vi, &vcol, &vcol_size)) != MESO_OK) {
            mesoi_rt_free(rt, data);
            return r;
        }
    }
    const size_t vcol_offset = (size + 15) & ~(size_t)15, total = vcol ? vcol_offset + vcol_size : size;
    mesoi_gl* gl = &rt->gl;
    GLint prev_vao = 0, prev_array = 0, stored = 0;
    gl->GetIntegerv(GL_VERTEX_ARRAY_BINDING, &prev_vao);
    gl->GetIntegerv(GL_ARRAY_BUFFER_BINDING, &prev_array);
    gl->GenVertexArrays(1, &o->vao);
    gl->GenBuffers(1, &o->buffer);
    gl->BindVertexArray(o->vao);
    gl->BindBuffer(GL_ARRAY_BUFFER, o->buffer);
    gl->BufferData(GL_ARRAY_BUFFER, (GLsizeiptr)total, vcol || rt->defer ? NULL : data, GL_STATIC_DRAW);
    if (rt->defer) { /* the data later (rt_transfer.c) */
        mesoi_defer_buffer(rt, o->buffer, 0, size, data);
        if (vcol)
            mesoi_defer_buffer(rt, o->buffer, vcol_offset, vcol_size, vcol);
    } else if (vcol) {
        gl->BufferSubData(GL_ARRAY_BUFFER, 0, (GLsizeiptr)size, data);
        gl->BufferSubData(GL_ARRAY_BUFFER, (GLintptr)vcol_offset, (GLsizeiptr)vcol_size, vcol);
    }
    gl->GetBufferParameteriv(GL_ARRAY_BUFFER, GL_BUFFER_SIZE, &stored);
    gl->BindBuffer(GL_ELEMENT_ARRAY_BUFFER, o->buffer);
    gl->VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, 12, NULL);
    gl->EnableVertexAttribArray(0);
    /* The integers as they are (511 x the unit normal): the shaders normalise. */
    gl->VertexAttribPointer(1, 4, GL_INT_2_10_10_10_REV, GL_FALSE, 4, (const void*)(uintptr_t)mg.normals_at);
    gl->EnableVertexAttribArray(1);
    const GLint nc = vi >= 0 ? (GLint)meso_file_chunk(f, (uint32_t)vi)->components : 0;
    if (vcol) {
        gl->VertexAttribPointer(2, nc, GL_UNSIGNED_BYTE, GL_TRUE, nc, (const void*)(uintptr_t)vcol_offset);
        gl->EnableVertexAttribArray(2);
    }
    gl->BindVertexArray((GLuint)prev_vao);
    gl->BindBuffer(GL_ARRAY_BUFFER, (GLuint)prev_array);
    mesoi_rt_free(rt, data);
    mesoi_rt_free(rt, vcol);
    /* No store (out of memory) shows in the buffer's size; the host's GL
     * error queue is read only on request. */
    const GLenum e = rt->check_gl_errors ? gl->GetError() : GL_NO_ERROR;
    if ((size_t)stored != total || e != GL_NO_ERROR) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "uploading object %u: %zu-byte buffer (GL error 0x%04x)",
                  object_id, total, e);
        gl->DeleteVertexArrays(1, &o->vao);
        gl->DeleteBuffers(1, &o->buffer);
        o->vao = o->buffer = 0;
        return MESO_ERR_GL;
    }
    o->index_count = (GLsizei)mg.index_count;
    o->indices_offset = mg.indices_at;
    o->index_type = mg.index_size == 2 ? GL_UNSIGNED_SHORT : GL_UNSIGNED_INT;
    o->vertex_colours = vcol ? (nc == 4 ? 1 : 2) : 0;
    rt->gpu_count += total;
    return MESO_OK;
}

meso_result mesoi_mesh_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                            uint32_t count)
{
    if (o->parts)
        return mesoi_parts_draw(rt, o->parts, d, inst, count);
    mesoi_draw ds;
    /* The G-buffer's normal faces the viewer and the hook takes the view
     * direction and point: both unproject the fragment (mesh_frag.glsl). */
    const int unproject = d->pass == MESO_PASS_GBUFFER || (d->pass == MESO_PASS_FORWARD && rt->hook);
    meso_result r = mesoi_draw_prepare(rt, d, unproject, inst != NULL, &ds);
    if (r != MESO_OK)
        return r;
    ds.stats = 0; /* the mesh shaders count nothing: stats come back unsupported */
    const mesoi_program* prog = mesh_program(rt, ds.pass);
    if (!prog)
        return MESO_ERR_GL;
    static const GLenum targets[1] = {GL_TEXTURE_BUFFER};
    GLuint bind[1] = {0};
    if (inst &&
        (r = mesoi_instances_upload(rt, &ds, o, d, inst, NULL, count, unproject, NULL, NULL, &bind[0])) != MESO_OK)
        return r;
    /* Meshes are drawn with the host's culling, not the ray casters' back
     * faces (raycast 0). */
    mesoi_draw_begin(rt, &ds, prog, 0, inst ? 1 : 0, targets, bind);
    /* A mirroring model turns the triangles' winding over: the host's
     * front faces (under MESO_STATE_HOST_OWNS taken to be counter-clockwise,
     * GL's default) become the other winding for this draw. */
    if (ds.mirrored)
        rt->gl.FrontFace(ds.restore && ds.prev_front == GL_CW ? GL_CCW : GL_CW);
    /* The light in world space, as the fragment shader takes it. */
    float light[3] = {0.3f, 0.8f, 0.5f};
    if (d->light_dir[0] != 0.0f || d->light_dir[1] != 0.0f || d->light_dir[2] != 0.0f)
        memcpy(light, d->light_dir, sizeof(light));
    const float len = sqrtf(light[0] * light[0] + light[1] * light[1] + light[2] * light[2]);
    for (int k = 0; k < 3; ++k)
        light[k] /= len;
    mesoi_gl* gl = &rt->gl;
    const GLint* u = prog->loc;
    gl->UniformMatrix4fv(u[MESOI_U_view], 1, GL_FALSE, d->view);
    gl->UniformMatrix4fv(u[MESOI_U_proj], 1, GL_FALSE, d->proj);
    gl->UniformMatrix4fv(u[MESOI_U_model], 1, GL_FALSE, ds.model);
    gl->Uniform3fv(u[MESOI_U_light_dir], 1, light);
    gl->Uniform1i(u[MESOI_U_has_color], o->vertex_colours);
    gl->BindVertexArray(o->vao);
    if (inst)
        gl->DrawElementsInstanced(GL_TRIANGLES, o->index_count, o->index_type,
                                  (const void*)(uintptr_t)o->indices_offset, (GLsizei)count);
    else
        gl->DrawElements(GL_TRIANGLES, o->index_count, o->index_type, (const void*)(uintptr_t)o->indices_offset);
    return mesoi_draw_end(rt, &ds, d->stats, "mesh");
}
