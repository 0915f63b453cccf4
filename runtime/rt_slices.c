/*
 * rt_slices.c — MESO_SHELL_SLICES: slice-based direct isosurface rendering
 * of shells, papers/volume-textures-lp-averaged-shells.md §5 ("Slice-based
 * direct isosurface rendering", "Algorithm details", Figures 11-13). The
 * shaders are runtime/shaders/shell_slices_{vert,frag}.glsl; their headers
 * say what was decided where the paper's text is garbled (slice levels
 * m/(M−1), α − ½ for height fields, the t3 formula checked, p3 on the ray).
 *
 * Slicing (MESO_SLICE_AXIS_VIEW, the paper's "direction closest to the view
 * direction"): per prism and draw, the family of slices the view ray crosses
 * most densely — levels of constant w, or planes of constant barycentric
 * λ_i across corner i — plus the prism's faces that are not slices of that
 * family; MESO_SLICE_AXIS_LEVELS always takes the levels. Which family and
 * why "densest" rather than "closest by angle": shell_slices_vert.glsl.
 * Slicing along the view direction itself (view-aligned planes) would need
 * Φ⁻¹ per fragment — the ray casters' cost — and is not done.
 *
 * Passes:
 *  - MESO_SLICE_NONE: one pass into the host's framebuffer, alpha test
 *    (discard α < ½) and the host's depth test; depth = the first slice
 *    inside.
 *  - MESO_SLICE_NORMAL / MESO_SLICE_TEXCOORD: three passes.
 *     1. into target A (colour 0: RGBA32F T1 = (s, t', w, α − ½); colour 1:
 *        RGBA32F the no-interpolation colour and window depth; depth: Z1),
 *        the same fragments as NONE with GL_LESS (GL_GREATER reversed-Z);
 *     2. into target B (colour: RGBA32F interpolated colour and window depth
 *        of the crossing; depth cleared to the near value, GL_GREATER
 *        (GL_LESS reversed-Z)): fragments outside
 *        (α < ½) and in front of Z1 — the furthest wins, the last slice
 *        outside (the paper's reversed depth test);
 *     3. a full-screen triangle into the host's framebuffer: B where pass 2
 *        found a slice outside, else A's colour 1, with gl_FragDepth and the
 *        host's depth function — so the slices compose with the host's geometry
 *        exactly as the ray casters do. (The paper renders pass 2 into the
 *        framebuffer with the depth test reversed; a host's depth buffer
 *        cannot be reversed under it, hence the offscreen target.)
 *    The target (2 framebuffers, 5 textures: 3 × 16 + 2 × 4 = 56 bytes a pixel)
 *    belongs to the meso_rt context, is created on the first two-pass draw,
 *    re-created whenever the viewport's size changes, and freed by
 *    meso_rt_destroy.
 */
#include "rt_internal.h"
#include "shaders_embedded.h"

#include <stdio.h>
#include <string.h>

enum { PASS_NONE = 0, PASS_FIRST, PASS_NORMAL, PASS_TEXCOORD, PASS_COMPOSITE, PASS_COUNT };
enum { TEX_A_T1 = 0, TEX_A_COLOUR, TEX_A_DEPTH, TEX_B_COLOUR, TEX_B_DEPTH, TEX_COUNT };
/* Units: the shell's six (rt_shell.c), then the target's two inputs. */
enum { UNIT_FIRST = SHELL_UNIT_COUNT, UNIT_SECOND, SLICE_UNITS };

/* Slice pass `pass` (SLICE_PASS) of draw pass `mpass`: SLICE_PASS 0 writes
 * through pass_out.glsl, the others have their own outputs (forward only). */
static const mesoi_program* slice_program(meso_rt* rt, meso_rt_pass mpass, int pass)
{
    mesoi_program* p = &rt->slice_programs[mpass][pass];
    if (p->id)
        return p;
    char head[512];
    /* MESO_SINGLE: never instanced, instance.glsl leaves the uniforms as they are */
    snprintf(head, sizeof(head), "%s#define MESO_TECHNIQUE %d\n#define SLICE_PASS %d\n#define MESO_SINGLE 1\n",
             mesoi_glsl_prelude(rt, 0),
             (int)MESO_SHELL_SLICES, pass);
    const char* vs[6] = {head, MESOI_GLSL_VERTEX_STAGE, mesoi_glsl_instance, mesoi_glsl_shell_common,
                         mesoi_glsl_shell_texfn, mesoi_glsl_shell_slices_vert};
    const char* pre[4] = {mesoi_glsl_instance, mesoi_glsl_shell_common, mesoi_glsl_raycast_common,
                          mesoi_glsl_shell_texfn};
    static const char* const names[MESO_PASS_COUNT][PASS_COUNT] = {
        {"slices none", "slices first pass", "slices normal", "slices texcoord", "slices composite"},
        {"slices none depth"},
        {"slices none gbuffer"}};
    static const char* const samplers[SLICE_UNITS] = {"u_verts", "u_index", "u_height", "u_volume",
                                                      "u_dist",  "u_color", "u_first",  "u_second"};
    const mesoi_program_src src = {.vs = vs, .vs_count = 6, .vs_file = "shell_slices_vert.glsl", .pre = pre,
                                   .pre_count = 4, .frag = mesoi_glsl_shell_slices_frag,
                                   .frag_file = "shell_slices_frag.glsl", .own_outputs = pass != PASS_NONE,
                                   .name = names[mpass][pass], .samplers = samplers, .sampler_count = SLICE_UNITS};
    return mesoi_program_build(rt, p, mpass, &src);
}

meso_result mesoi_slices_prepare(meso_rt* rt, meso_rt_pass mpass)
{
    for (int pass = 0; pass < (mpass == MESO_PASS_FORWARD ? PASS_COUNT : 1); ++pass)
        if (!slice_program(rt, mpass, pass))
            return MESO_ERR_GL;
    return MESO_OK;
}

static void target_free(meso_rt* rt)
{
    if (rt->slice_fbo[0])
        rt->gl.DeleteFramebuffers(2, rt->slice_fbo);
    if (rt->slice_tex[0])
        rt->gl.DeleteTextures(TEX_COUNT, rt->slice_tex);
    memset(rt->slice_fbo, 0, sizeof(rt->slice_fbo));
    memset(rt->slice_tex, 0, sizeof(rt->slice_tex));
    rt->slice_size[0] = rt->slice_size[1] = 0;
}

void mesoi_slices_destroy(meso_rt* rt)
{
    for (int m = 0; m < MESO_PASS_COUNT; ++m)
        for (int p = 0; p < PASS_COUNT; ++p)
            mesoi_program_delete(rt, &rt->slice_programs[m][p]);
    target_free(rt);
}

/* The offscreen target at w × h (re)created; textures are bound on the
 * active unit while they are made (the caller restores it). 0 on failure. */
static int target_ensure(meso_rt* rt, GLint w, GLint h)
{
    if (rt->slice_fbo[0] && rt->slice_size[0] == w && rt->slice_size[1] == h)
        return 1;
    target_free(rt);
    mesoi_gl* gl = &rt->gl;
    /* No data, but a host's bound unpack buffer would be read from. */
    mesoi_unpack unpack;
    mesoi_unpack_default(rt, &unpack);
    gl->GenTextures(TEX_COUNT, rt->slice_tex);
    for (int t = 0; t < TEX_COUNT; ++t) {
        const int depth = t == TEX_A_DEPTH || t == TEX_B_DEPTH;
        gl->BindTexture(GL_TEXTURE_2D, rt->slice_tex[t]);
        gl->TexImage2D(GL_TEXTURE_2D, 0, depth ? GL_DEPTH_COMPONENT32F : GL_RGBA32F, w, h, 0,
                       depth ? GL_DEPTH_COMPONENT : GL_RGBA, GL_FLOAT, NULL);
        gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
        gl->TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    }
    mesoi_unpack_restore(rt, &unpack);
    gl->GenFramebuffers(2, rt->slice_fbo);
    static const GLenum bufs[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
    int ok = 1;
    for (int f = 0; f < 2; ++f) {
        gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, rt->slice_fbo[f]);
        const GLuint c0 = rt->slice_tex[f == 0 ? TEX_A_T1 : TEX_B_COLOUR];
        const GLuint zt = rt->slice_tex[f == 0 ? TEX_A_DEPTH : TEX_B_DEPTH];
        gl->FramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, c0, 0);
        if (f == 0)
            gl->FramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D,
                                     rt->slice_tex[TEX_A_COLOUR], 0);
        gl->FramebufferTexture2D(GL_DRAW_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, zt, 0);
        gl->DrawBuffers(f == 0 ? 2 : 1, bufs);
        ok = ok && gl->CheckFramebufferStatus(GL_DRAW_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE;
    }
    if (!ok) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_GL_ERROR, "slices: offscreen target %dx%d incomplete", w, h);
        target_free(rt);
        return 0;
    }
    rt->slice_size[0] = w;
    rt->slice_size[1] = h;
    return 1;
}

/* Binds pass program `p` with the common uniforms (mesoi_draw_use), the
 * viewport of the target it draws into, then the slice uniforms. */
static void use_pass(meso_rt* rt, const mesoi_draw* ds, const mesoi_program* p, const mesoi_shell* s,
                     const meso_rt_shell_draw* k, const GLint viewport[4])
{
    mesoi_gl* gl = &rt->gl;
    mesoi_draw_use(rt, ds, p);
    const float vp[4] = {(float)viewport[0], (float)viewport[1], (float)viewport[2], (float)viewport[3]};
    gl->Uniform4fv(p->loc[MESOI_U_viewport], 1, vp);
    gl->Uniform1i(p->loc[MESOI_U_tex_kind], s->tex_kind);
    gl->Uniform1i(p->loc[MESOI_U_has_color], s->color_tex != 0);
    gl->Uniform3fv(p->loc[MESOI_U_color_scale], 1, s->color_scale);
    gl->Uniform3fv(p->loc[MESOI_U_tex_size], 1, s->tex_size);
    gl->Uniform1i(p->loc[MESOI_U_slices], k->slices > 0 ? k->slices : 16);
    gl->Uniform1i(p->loc[MESOI_U_slice_axis], (GLint)k->slice_axis);
    gl->Uniform1f(p->loc[MESOI_U_uv_scale], k->uv_scale > 0.0f ? k->uv_scale : 1.0f);
    gl->Uniform1i(p->loc[MESOI_U_prism_count], (GLint)s->triangle_count);
}

meso_result mesoi_slices_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d)
{
    const mesoi_shell* s = o->shell;
    const meso_rt_shell_draw* k = &d->shell;
    if (d->stats)
        memset(d->stats, 0, sizeof(*d->stats));
    const int slices = k->slices > 0 ? k->slices : 16;
    if (slices < 2 || slices > 1024 || (unsigned)k->slice_interp >= MESO_SLICE_INTERP_COUNT ||
        (unsigned)k->slice_axis >= MESO_SLICE_AXIS_COUNT) {
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw: slices %d (2..1024), interp %d, axis %d", k->slices, (int)k->slice_interp,
                  (int)k->slice_axis);
        return MESO_ERR_INVALID_ARG;
    }
    meso_rt_draw_desc dd = *d;
    dd.stats = NULL; /* the slice shaders count nothing */
    mesoi_draw ds;
    meso_result r = mesoi_draw_prepare(rt, &dd, 1, 0, &ds);
    if (r != MESO_OK)
        return r;
    const int two_pass = k->slice_interp != MESO_SLICE_NONE;
    if (two_pass && ds.pass != MESO_PASS_FORWARD) {
        /* Their depth is the interpolated crossing, composited through the
         * offscreen target: not a depth-only or G-buffer draw. */
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw: MESO_SHELL_SLICES draws depth and G-buffer passes with MESO_SLICE_NONE only");
        return MESO_ERR_UNSUPPORTED;
    }
    const int second = k->slice_interp == MESO_SLICE_NORMAL ? PASS_NORMAL : PASS_TEXCOORD;
    const mesoi_program* prog = slice_program(rt, ds.pass, two_pass ? PASS_FIRST : PASS_NONE);
    if (!prog || (two_pass && (!slice_program(rt, ds.pass, second) || !slice_program(rt, ds.pass, PASS_COMPOSITE))))
        return MESO_ERR_GL;
    mesoi_gl* gl = &rt->gl;
    static const GLenum unit_target[SLICE_UNITS] = {GL_TEXTURE_BUFFER, GL_TEXTURE_BUFFER, GL_TEXTURE_2D,
                                                    GL_TEXTURE_3D,     GL_TEXTURE_3D,     GL_TEXTURE_3D,
                                                    GL_TEXTURE_2D,     GL_TEXTURE_2D};
    const GLuint bind[SLICE_UNITS] = {s->vert_tex, s->index_tex, s->tex_kind == 1 ? s->func_tex : 0,
                                      s->tex_kind == 2 ? s->func_tex : 0, 0, s->color_tex, 0, 0};
    mesoi_draw_begin(rt, &ds, prog, 0, SLICE_UNITS, unit_target, bind);
    gl->Disable(GL_CULL_FACE); /* slices are seen from both sides */
    /* Triangles a prism: levels, M slices and 3 side quads; the view
     * family, 2 per slice (a level uses one) and 2 caps and 3 side quads. */
    const int64_t per_prism = k->slice_axis == MESO_SLICE_AXIS_LEVELS ? slices + 6 : 2 * (int64_t)slices + 8;
    const int64_t count64 = 3 * per_prism * (int64_t)s->triangle_count;
    if (count64 > INT32_MAX) { /* a GLsizei: refused before GL raises GL_INVALID_VALUE */
        mesoi_log(rt, MESO_LOG_ERROR, MESO_LOGITEM_INVALID_ARGUMENT,
                  "meso_rt_draw: %d slices of %u prisms are more than one draw call holds", slices,
                  s->triangle_count);
        mesoi_draw_end(rt, &ds, NULL, "slices");
        return MESO_ERR_INVALID_ARG;
    }
    const GLsizei count = (GLsizei)count64;
    if (!two_pass) {
        use_pass(rt, &ds, prog, s, k, ds.viewport);
        gl->DrawArrays(GL_TRIANGLES, 0, count);
        return mesoi_draw_end(rt, &ds, NULL, "slices");
    }

    /* The last pass draws into the host's framebuffer: its binding is read
     * under either state policy. */
    const GLint w = ds.viewport[2] > 0 ? ds.viewport[2] : 1, h = ds.viewport[3] > 0 ? ds.viewport[3] : 1;
    GLint prev_fbo = 0;
    gl->GetIntegerv(GL_DRAW_FRAMEBUFFER_BINDING, &prev_fbo);
    const GLboolean prev_blend = ds.restore ? gl->IsEnabled(GL_BLEND) : GL_FALSE;
    /* The host's depth function for the last pass: given, or the one
     * begin saved, or the convention's. */
    const GLenum host_func = ds.depth_func ? ds.depth_func : ds.restore ? (GLenum)ds.prev_func : mesoi_near_func(&ds);
    if (!target_ensure(rt, w, h)) {
        gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)prev_fbo);
        mesoi_draw_end(rt, &ds, NULL, "slices");
        return MESO_ERR_GL;
    }
    const GLint local[4] = {0, 0, w, h};
    gl->Disable(GL_BLEND);
    gl->Viewport(0, 0, w, h);

    /* 1: the first slice inside, T1 and Z1 (nearest wins). Colour 1's alpha
     * holds the window depth, 2 where nothing was drawn (depths are 0..1). */
    static const float none[4] = {0.0f, 0.0f, 0.0f, 2.0f}, zero[4] = {0.0f, 0.0f, 0.0f, 0.0f};
    const float far = mesoi_far_clear(&ds), near = 1.0f - far;
    gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, rt->slice_fbo[0]);
    gl->ClearBufferfv(GL_COLOR, 0, zero);
    gl->ClearBufferfv(GL_COLOR, 1, none);
    gl->ClearBufferfv(GL_DEPTH, 0, &far);
    gl->DepthFunc(mesoi_near_func(&ds));
    use_pass(rt, &ds, prog, s, k, local);
    gl->DrawArrays(GL_TRIANGLES, 0, count);

    /* 2: the last slice outside in front of Z1 (reversed depth test: the
     * furthest wins). */
    gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, rt->slice_fbo[1]);
    gl->ClearBufferfv(GL_COLOR, 0, none);
    gl->ClearBufferfv(GL_DEPTH, 0, &near);
    gl->DepthFunc(ds.reversed ? GL_LESS : GL_GREATER);
    gl->ActiveTexture(GL_TEXTURE0 + UNIT_FIRST);
    gl->BindTexture(GL_TEXTURE_2D, rt->slice_tex[TEX_A_T1]);
    gl->ActiveTexture(GL_TEXTURE0 + UNIT_SECOND);
    gl->BindTexture(GL_TEXTURE_2D, rt->slice_tex[TEX_A_DEPTH]);
    use_pass(rt, &ds, slice_program(rt, ds.pass, second), s, k, local);
    gl->DrawArrays(GL_TRIANGLES, 0, count);

    /* 3: composite into the host's framebuffer with its depth test. */
    gl->BindFramebuffer(GL_DRAW_FRAMEBUFFER, (GLuint)prev_fbo);
    gl->Viewport(ds.viewport[0], ds.viewport[1], ds.viewport[2], ds.viewport[3]);
    if (prev_blend)
        gl->Enable(GL_BLEND);
    gl->DepthFunc(host_func);
    gl->ActiveTexture(GL_TEXTURE0 + UNIT_FIRST);
    gl->BindTexture(GL_TEXTURE_2D, rt->slice_tex[TEX_A_COLOUR]);
    gl->ActiveTexture(GL_TEXTURE0 + UNIT_SECOND);
    gl->BindTexture(GL_TEXTURE_2D, rt->slice_tex[TEX_B_COLOUR]);
    use_pass(rt, &ds, slice_program(rt, ds.pass, PASS_COMPOSITE), s, k, ds.viewport);
    gl->DrawArrays(GL_TRIANGLES, 0, 3);
    return mesoi_draw_end(rt, &ds, NULL, "slices");
}
