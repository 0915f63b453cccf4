/* rt_internal.h — state shared by the runtime's files (internal, mesoi_ prefix). */
#ifndef MESO_RT_INTERNAL_H
#define MESO_RT_INTERNAL_H

#include "meso_rt.h"
#include "rt_gl.h"

/* One uploaded object. The slot index is id & 0xFFFF, the generation
 * id >> 16, so handles to released slots are detected. */
typedef struct mesoi_object {
    uint32_t generation; /* 1..0xFFFF, bumped each time the slot is reused */
    uint32_t live;       /* 0 = slot free */
    uint32_t kind;       /* meso_object_kind */
    GLuint vao, buffer;
    struct mesoi_shell* shell; /* MESO_OBJECT_SHELL only */
    struct mesoi_frusta* frusta; /* MESO_OBJECT_FRUSTA only */
    struct mesoi_cells* cells;   /* MESO_OBJECT_CELLS only (vao/buffer: its base mesh) */
    GLsizei index_count;
    uint64_t indices_offset;
    float bbox_min[3], bbox_max[3];
} mesoi_object;

struct meso_rt {
    meso_allocator alloc;
    meso_log_fn log_fn;
    void* log_user;
    mesoi_gl gl;
    int gl_version; /* major*10+minor */
    int gles;       /* 1 on an OpenGL ES context (GL_VERSION "OpenGL ES ...") */
    /* ES only (desktop: both 1, core since 3.0): GL_EXT_texture_norm16 (R16,
     * RG16 textures) and GL_OES_texture_float_linear (linear R32F); without
     * them the uploads convert (rt_common.c: upload formats). */
    int norm16, float_linear;
    int stats_ok; /* fragment shaders can count into a shader storage buffer (GL 4.3, or ES with fragment SSBOs) */
    GLuint mesh_program;
    GLint u_view, u_proj, u_model, u_light_dir; /* of mesh_program */
    GLuint shell_programs[2][MESO_SHELL_TECHNIQUE_COUNT]; /* [stats][technique], compiled on first use */
    GLuint frusta_programs[2];                            /* [stats], compiled on first use */
    GLuint cells_programs[2];                             /* [stats], compiled on first use */
    GLuint slice_programs[5]; /* MESO_SHELL_SLICES, per pass (shell_slices_frag.glsl SLICE_PASS) */
    GLuint slice_fbo[2];      /* the two-pass slice variants' offscreen target (rt_slices.c) */
    GLuint slice_tex[5];
    GLint slice_size[2];      /* its width and height: the viewport's */
    GLuint empty_vao;   /* shells and frusta draw from gl_VertexID alone */
    GLuint stats_buffer; /* 3 counters (OpenGL 4.3 / ES 3.1 shader storage) */
    mesoi_object* objects;
    uint32_t object_capacity;
};

/* rt_shell.c: one uploaded shell (rt_slices.c draws it too). */
typedef struct mesoi_shell {
    uint32_t vertex_count, triangle_count, layers;
    float* positions; /* 3 per vertex (CPU copy for updates) */
    float* directors; /* 3 per vertex per layer */
    float* uvs;       /* 2 per vertex */
    GLuint vert_buf, vert_tex, index_buf, index_tex;
    GLuint func_tex, dist_tex;
    int tex_kind; /* 0 none, 1 height (2D), 2 density (3D) */
    float tex_size[3];
    /* Stored frames (ANIM, TXFR, DSFR; FORMAT.md §7.2 "Animated texture
     * functions"), host copies: frame k of the function at k * fn_bytes,
     * of the distance map at k * dist_bytes. anim.frame_count 0: none. */
    meso_anim_record anim;
    uint8_t *fn_frames, *dist_frames;
    meso_rt_shell_texture frame_desc; /* dims and types of one frame (data pointers unset) */
    size_t fn_bytes, dist_bytes;
    uint32_t shown_frame; /* the stored frame uploaded last; UINT32_MAX after meso_rt_shell_set_texture */
} mesoi_shell;

enum { SHELL_UNIT_VERTS = 0, SHELL_UNIT_INDEX, SHELL_UNIT_HEIGHT, SHELL_UNIT_VOLUME, SHELL_UNIT_DIST, SHELL_UNIT_COUNT };

meso_result mesoi_slices_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d); /* rt_slices.c */
/* Deletes the slice programs and the offscreen target (rt_slices.c). */
void mesoi_slices_destroy(meso_rt* rt);

meso_result mesoi_shell_load(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
void mesoi_shell_release(meso_rt* rt, mesoi_object* o);
meso_result mesoi_shell_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d);
void mesoi_shell_programs_destroy(meso_rt* rt);

/* rt_frusta.c */
meso_result mesoi_frusta_load(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
void mesoi_frusta_release(meso_rt* rt, mesoi_object* o);
meso_result mesoi_frusta_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d);
void mesoi_frusta_programs_destroy(meso_rt* rt);
/* meso_rt_frusta_set_pose without the upload: the pose rebuild and the
 * bounding geometry on the host copy (tests/bench time the two parts). */
meso_result mesoi_frusta_pose_host(meso_rt* rt, meso_rt_object obj, const float* node_positions, uint32_t node_count);

/* rt_cells.c */
meso_result mesoi_cells_load(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
void mesoi_cells_release(meso_rt* rt, mesoi_object* o);
meso_result mesoi_cells_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d);
void mesoi_cells_programs_destroy(meso_rt* rt);

/* rt_common.c: chunks and uploads */
/* Index of the finest-level chunk of `type` for `object`, or -1. */
int32_t mesoi_find_chunk(meso_file* f, uint32_t type, uint32_t object);
/* Reads a whole chunk (validated by meso_file_read_chunk) into a fresh
 * allocation; logs and fails cleanly. */
meso_result mesoi_read_whole(meso_rt* rt, meso_file* f, int32_t ci, void** out, size_t* size);
/* Uploads a TX2D / TX3D / DIST / RELF chunk of one component as a 2D or 3D
 * texture, linear (or `nearest`) and repeating in s and t. */
meso_result mesoi_upload_texture(meso_rt* rt, meso_file* f, int32_t ci, int dims3, int nearest, GLuint* out);
/* The same from texels in memory: a new texture (*out) of `dims` values
 * of `dtype` (U8, U16, or F32 when `nearest`); the unit's 2D/3D binding and
 * the unpack alignment are restored. MESO_ERR_UNSUPPORTED for other types. */
meso_result mesoi_upload_texels(meso_rt* rt, const uint32_t dims[3], uint16_t dtype, int dims3, int nearest,
                                const void* data, GLuint* out);
/* A texture buffer over a new buffer object holding `size` bytes of `data`. */
GLuint mesoi_texture_buffer(meso_rt* rt, GLenum format, const void* data, size_t size, GLuint* buf);
/* Around a sequence of uploads: begin saves the texture buffer binding and
 * clears stale GL errors (returns the binding); end restores it and turns a
 * GL error raised meanwhile into MESO_ERR_GL (logged as "WHAT: GL error"),
 * else returns r. */
GLint mesoi_upload_begin(meso_rt* rt);
meso_result mesoi_upload_end(meso_rt* rt, GLint prev, meso_result r, const char* what);
/* Overwrites the first `size` bytes of buffer `buf` (animation updates). */
meso_result mesoi_buffer_update(meso_rt* rt, GLuint buf, const void* data, size_t size, const char* what);

/* rt_common.c: one draw, of any kind. prepare (no GL state touched; fails
 * on a singular object -> clip matrix when `need_inverse`, as the ray
 * casters need it) → begin (saves the state meso_rt_draw promises to
 * restore, binds the textures, the counters and `program` with its common
 * uniforms u_mvp, u_inv_mvp, u_viewport, u_light_obj, u_albedo, and sets
 * depth test GL_LESS with writes, front-face culling and the empty vertex
 * array) → the kind's own state, uniforms and draw call → end (reads the
 * counters, restores). */
#define MESOI_DRAW_MAX_UNITS 8
typedef struct mesoi_draw {
    float model[16];            /* object -> world: desc->model, or identity when it is all zero */
    float mvp[16], inv_mvp[16]; /* object -> clip and back (inv_mvp zero when singular) */
    double proj11;              /* |proj[1][1]| */
    double model_scale;         /* length of the model matrix's first column */
    GLint viewport[4];
    float light_obj[3], albedo[3];
    int stats; /* the shaders count work (rt->stats_ok and desc->stats) */
    int units;
    GLenum target[MESOI_DRAW_MAX_UNITS];
    GLint prev_bind[MESOI_DRAW_MAX_UNITS];
    GLint prev_program, prev_vao, prev_func, prev_mask, prev_active, prev_cull_mode, prev_front, prev_ssbo;
    GLboolean prev_test, prev_cull;
} mesoi_draw;
meso_result mesoi_draw_prepare(meso_rt* rt, const meso_rt_draw_desc* d, int need_inverse, mesoi_draw* out);
void mesoi_draw_begin(meso_rt* rt, mesoi_draw* s, GLuint program, int units, const GLenum* targets,
                      const GLuint* textures);
meso_result mesoi_draw_end(meso_rt* rt, mesoi_draw* s, meso_rt_draw_stats* stats, const char* what);

/* rt_common.c: what every shader starts with: the #version line (desktop:
 * "330 core", "430 core" with `stats`; ES: "320 es" and default precisions
 * highp for floats, ints and every sampler type the shaders use), then
 * "#define MESO_STATS 1" with `stats`. A static string. */
const char* mesoi_glsl_prelude(const meso_rt* rt, int stats);
/* An allocation of `count` floats v / 65535 from `count` host-order U16 texels, for contexts without 16-bit normalised textures
 * (ES without GL_EXT_texture_norm16); NULL (logged) when out of memory. */
float* mesoi_unorm16_to_float(meso_rt* rt, const void* texels, size_t count);

/* rt_common.c: shaders. compile: one shader from `count` sources, 0
 * (logged with `name`) on failure; link: links and deletes the two shaders
 * (either may be 0, then both are deleted), 0 (logged) on failure. */
GLuint mesoi_compile(meso_rt* rt, GLenum type, const char* const* src, int count, const char* name);
GLuint mesoi_link(meso_rt* rt, GLuint vs, GLuint fs, const char* name);

/* rt_mesh.c */
/* The object's MESH chunk into o->vao / o->buffer / index_count (positions
 * at attribute 0, normals at 1, the chunk's own layout). Cells use it for
 * their base mesh. */
meso_result mesoi_mesh_upload(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
meso_result mesoi_mesh_program_create(meso_rt* rt);
meso_result mesoi_mesh_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d);

/* rt_objects.c */
mesoi_object* mesoi_lookup(const meso_rt* rt, meso_rt_object h);
void mesoi_objects_destroy(meso_rt* rt);

/* meso_rt.c */
void* mesoi_rt_alloc(meso_rt* rt, size_t size);
void mesoi_rt_free(meso_rt* rt, void* p);
/* Log an item with a printf-style detail; silent without a logger. */
void mesoi_log(meso_rt* rt, meso_log_level level, meso_log_item item, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

#endif
