/* rt_internal.h — state shared by the runtime's files (internal, mesoi_ prefix). */
#ifndef MESO_RT_INTERNAL_H
#define MESO_RT_INTERNAL_H

#include "meso_rt.h"
#include "rt_gl.h"
#include "rt_mesh_repack.h"

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
    GLenum index_type; /* GL_UNSIGNED_SHORT or GL_UNSIGNED_INT (rt_mesh_repack.c) */
    uint64_t indices_offset;
    int vertex_colours; /* MESO_OBJECT_MESH: a VCOL in the buffer (attribute 2): 0 none, 1 albedo and
                           occlusion, 2 occlusion alone */
    float bbox_min[3], bbox_max[3];
    uint64_t gpu_bytes;  /* what its textures and buffers hold (mesoi_load_slot, mesoi_parts_upload) */
    struct mesoi_levels* levels; /* meso_rt_load_object_levels: the levels, each its own slot (rt_levels.c);
                                    such an object has no GL resources of its own */
    struct mesoi_parts* parts;   /* the slot a parts pick hands out (rt_parts.c): its mesh draw draws the
                                    parts that pick chose; no GL resources of its own */
} mesoi_object;

/* Every uniform any of the programs declares. Locations are looked up once,
 * when a program links (mesoi_program_init), so a draw sets uniforms
 * without asking GL for names; a program without one has location -1, which
 * glUniform* ignores. */
#define MESOI_UNIFORMS(X)                                                                                  \
    X(mvp) X(inv_mvp) X(viewport) X(light_obj) X(albedo) X(depth_ndc) /* every kind (mesoi_draw_begin) */ \
    X(view) X(proj) X(model) X(light_dir)                              /* mesh */                          \
    X(uv_scale) X(tex_kind) X(has_dist) X(tex_size) X(err_scale) X(max_steps) X(bisect_steps)             \
    X(segment_steps) X(fixed_step) X(min_step) X(slices) X(slice_axis) X(prism_count) /* shell, slices */                \
    X(has_color) X(color_scale) X(hull_reject) X(walk) X(near) X(no_bottom)                        /* shell colour, hull rejection */  \
    X(relief_size) X(relief_steps) X(color_size) X(ball_color)          /* frusta */                        \
    X(has_env) X(env_rot) X(origin) X(h) X(tiles) X(res) X(class_words) X(words) X(map_full) X(id_bits) X(from_near)  \
    X(mode) X(bounces) X(refl) X(ior) X(tau) X(step) X(bisect) X(grid_size) X(footprint_rays) /* cells */                              \
    X(instanced) X(instance_base)                                      /* instance.glsl */

enum {
#define MESOI_X_ENUM(name) MESOI_U_##name,
    MESOI_UNIFORMS(MESOI_X_ENUM)
#undef MESOI_X_ENUM
        MESOI_U_COUNT
};

/* A linked program and its uniform locations. id 0: not built (yet). */
typedef struct mesoi_program {
    GLuint id;
    GLint loc[MESOI_U_COUNT];
    int instanced; /* the value u_instanced holds (GL starts uniforms at 0), so single draws set it only
                      after an instanced one */
} mesoi_program;

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
    int hull_reject_ok; /* shells can reject hull fragments behind a hit through an image (rt_shell.c) */
    meso_rt_state_policy state_policy;
    int check_gl_errors;
    int mipmaps; /* meso_rt_desc.texture_filter is MESO_FILTER_MIPMAP: appearance textures get mip levels */
    /* Programs per meso_rt_pass (shaders/pass_out.glsl MESO_PASS), built on
     * first use or in meso_rt_prepare. */
    mesoi_program mesh_programs[MESO_PASS_COUNT];
    mesoi_program shell_programs[MESO_PASS_COUNT][2][MESO_SHELL_TECHNIQUE_COUNT]; /* [pass][stats][technique] */
    mesoi_program frusta_programs[MESO_PASS_COUNT][2];                            /* [pass][stats] */
    mesoi_program cells_programs[MESO_PASS_COUNT][2];                             /* [pass][stats] */
    /* MESO_SHELL_SLICES: [pass][shell_slices_frag.glsl SLICE_PASS]; passes
     * other than forward have SLICE_PASS 0 (MESO_SLICE_NONE) only. */
    mesoi_program slice_programs[MESO_PASS_COUNT][5];
    char* hook;            /* meso_rt_desc.shading_hook, copied; NULL: built-in shading */
    GLuint hook_binding;   /* meso_rt_desc.shading_hook_binding */
    GLuint slice_fbo[2];      /* the two-pass slice variants' offscreen target (rt_slices.c) */
    GLuint slice_tex[5];
    GLint slice_size[2];      /* its width and height: the viewport's */
    GLuint empty_vao;   /* shells and frusta draw from gl_VertexID alone */
    GLuint stats_buffer; /* 4 counters (OpenGL 4.3 / ES 3.1 shader storage) */
    GLuint hit_image;          /* the shells' nearest hit per pixel (rt_shell.c), made on first use */
    GLint hit_size[2];         /* its width and height */
    GLuint inst_buf, inst_tex; /* per-instance data of instanced draws (rt_instances.c), made on first use */
    size_t inst_capacity;      /* bytes in inst_buf */
    GLint inst_max_texels;     /* GL_MAX_TEXTURE_BUFFER_SIZE, asked on the first instanced draw */
    float* inst_texels;        /* host staging for it */
    size_t inst_texels_capacity; /* floats */
    GLuint list_program;       /* inside meso_rt_draw_list: the program bound last (0: none yet) */
    int in_list;               /* inside meso_rt_draw_list: the list saved the state, the draws do not */
    uint16_t load_lod;         /* the level a load reads (mesoi_find_chunk); 0 outside rt_levels.c's loads */
    /* The memory budget of levelled objects (rt_levels.c). */
    uint64_t budget, bytes_resident, bytes_wanted, frame, evictions; /* bytes_resident: GPU bytes of the
                                                                         uploaded levels and part levels */
    uint64_t gpu_count;        /* GPU bytes every object texture and buffer created so far holds (counted where
                                  rt_common.c, rt_mesh.c and rt_cells.c make them): a load's are the difference
                                  across it */
    double tau_scale;
    /* Streaming (rt_stream.c): meso_rt_desc.stream_requests, every request
     * not freed (oldest first), the one being uploaded, levels uploaded. */
    int stream_requests;
    struct meso_rt_request* requests;
    struct meso_rt_request* prefetch;
    uint64_t stream_uploads;
    struct mesoi_transfers* defer; /* non-NULL: uploads queue their data there (rt_transfer.c) */
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
    /* Colour (COLR + CMAP, FORMAT.md §7.2 "Shell colour"): a 3D SRGB8_ALPHA8
     * texture (depth 1 for 2D colour), looked up at (s, t', w) * color_scale. */
    GLuint color_tex;     /* 0: none (u_albedo) */
    float color_scale[3]; /* the CMAP scale, 1 */
    /* Hull rejection (rt_shell.c): the MESH's triangles as read (host
     * copy); order_buf holds them sorted along the view axis's cell
     * sort_cell (object space), re-sorted when the view turns into another
     * cell or the shell moves (order_stale). */
    uint32_t* indices;
    GLuint order_buf, order_tex; /* the sorted copy (R32UI texture buffer); 0 without hull rejection */
    /* The walk (rt_prism_walk.c): neighbours[3 t + k] the triangle across
     * side k of triangle t (-1: none), host copy; adj_buf (R32I texture
     * buffer, with order_buf) the same per slot of order_buf, as slots. */
    int32_t* neighbours;
    /* mates[3 t + k]: the side (3 u + m: side m of triangle u) across side
     * k of triangle t on the welded corners, folded or not (-1: none);
     * found once, kept while meso_rt_shell_update leaves the corners it
     * welded equal */
    int32_t* mates;
    GLuint adj_buf, adj_tex;
    float box_min[3], box_max[3]; /* every prism corner lies inside (fill_vertex_texels) */
    int closed;                   /* every edge of two triangles (mesoi_prism_topology) */
    int32_t sort_cell;
    int order_stale;
    /* Set by a parts draw (rt_parts.c) for one draw: only these prisms
     * (base triangles), sorted into order_buf as the whole set is;
     * sorted_key: the subset order_buf holds (0 the whole set), of
     * sorted_count prisms (a subset's entries that are not triangles of
     * this shell, from a file not checked in full, are left out). */
    const uint32_t* subset;
    uint32_t subset_count, sorted_count;
    uint64_t subset_key, sorted_key;
} mesoi_shell;

enum {
    SHELL_UNIT_VERTS = 0,
    SHELL_UNIT_INDEX,
    SHELL_UNIT_HEIGHT,
    SHELL_UNIT_VOLUME,
    SHELL_UNIT_DIST,
    SHELL_UNIT_COLOR,
    SHELL_UNIT_COUNT
};

meso_result mesoi_slices_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d); /* rt_slices.c */
/* Deletes the slice programs and the offscreen target (rt_slices.c). */
void mesoi_slices_destroy(meso_rt* rt);

meso_result mesoi_shell_load(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
/* The walk's neighbours (rt_prism_walk.c). mesoi_prism_topology fills
 * mates[3 t + k] (3 per triangle) with the side 3 u + m (side m of
 * triangle u) across side k of triangle t on the welded corners, -1 for
 * none; *closed: every edge has two triangles. mesoi_prism_topology_holds:
 * whether every pair of mates still shares its side's corners bit for bit
 * (after a shape update). mesoi_prism_neighbours: out = the mates whose
 * prisms are both regular (not folded), -1 elsewhere. */
meso_result mesoi_prism_topology(meso_rt* rt, const mesoi_shell* s, int32_t* mates, int* closed);
int mesoi_prism_topology_holds(const mesoi_shell* s, const int32_t* mates);
meso_result mesoi_prism_neighbours(meso_rt* rt, const mesoi_shell* s, const int32_t* mates, int32_t* out);
void mesoi_shell_release(meso_rt* rt, mesoi_object* o);
/* The kinds' draws: one object (inst NULL: desc->model, uniforms), or
 * `count` instances in one instanced draw call (rt_instances.c). */
meso_result mesoi_shell_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                             uint32_t count);
void mesoi_shell_programs_destroy(meso_rt* rt);
/* Build every shell program of `pass` (stats: the counting variants;
 * without, the slice programs of the pass too): meso_rt_prepare. */
meso_result mesoi_shell_prepare(meso_rt* rt, int stats, meso_rt_pass pass);
meso_result mesoi_slices_prepare(meso_rt* rt, meso_rt_pass pass); /* rt_slices.c */

/* rt_frusta.c */
meso_result mesoi_frusta_load(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
void mesoi_frusta_release(meso_rt* rt, mesoi_object* o);
meso_result mesoi_frusta_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                              uint32_t count);
void mesoi_frusta_programs_destroy(meso_rt* rt);
meso_result mesoi_frusta_prepare(meso_rt* rt, int stats, meso_rt_pass pass);
/* meso_rt_frusta_set_pose without the upload: the pose rebuild and the
 * bounding geometry on the host copy (tests/bench time the two parts). */
meso_result mesoi_frusta_pose_host(meso_rt* rt, meso_rt_object obj, const float* node_positions, uint32_t node_count);

/* rt_cells.c */
meso_result mesoi_cells_load(meso_rt* rt, meso_file* f, uint32_t object_id, mesoi_object* o);
void mesoi_cells_release(meso_rt* rt, mesoi_object* o);
meso_result mesoi_cells_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                             uint32_t count);
void mesoi_cells_programs_destroy(meso_rt* rt);
meso_result mesoi_cells_prepare(meso_rt* rt, int stats, meso_rt_pass pass);

/* rt_common.c: chunks and uploads */
/* Index of the chunk of `type` for `object` that the level being loaded
 * (rt->load_lod; 0: the finest) draws, or -1. */
int32_t mesoi_find_chunk(const meso_rt* rt, meso_file* f, uint32_t type, uint32_t object);
/* Reads a whole chunk (validated by meso_file_read_chunk) into a fresh
 * allocation; logs and fails cleanly. */
meso_result mesoi_read_whole(meso_rt* rt, meso_file* f, int32_t ci, void** out, size_t* size);
/* Uploads a TX2D / TX3D / DIST / RELF chunk of one component as a 2D or 3D
 * texture, linear (or `nearest`) and repeating in s and t; linear ones get
 * their mip levels (trilinear) unless the context is MESO_FILTER_LEVEL0,
 * nearest ones (distance maps: conservative for level 0 only) never. */
meso_result mesoi_upload_texture(meso_rt* rt, meso_file* f, int32_t ci, int dims3, int nearest, GLuint* out);
/* The same from texels in memory: a new texture (*out) of `dims` values
 * of `dtype` (U8, U16, or F32 when `nearest`); the unit's 2D/3D binding and
 * the unpack state are restored; MESO_ERR_GL (logged) when GL made no level 0. MESO_ERR_UNSUPPORTED for other types. */
meso_result mesoi_upload_texels(meso_rt* rt, const uint32_t dims[3], uint16_t dtype, int dims3, int nearest,
                                const void* data, GLuint* out);
/* An RGBA8 colour chunk (COLR) as a 3D (or, !dims3, 2D: dims[2] 1)
 * GL_SRGB8_ALPHA8 texture (fetches are linear), filtered linearly with mip
 * levels as mesoi_upload_texture, repeating in s and t and clamped in r;
 * bindings and unpack state restored as mesoi_upload_texels. */
meso_result mesoi_upload_srgba8(meso_rt* rt, const uint32_t dims[3], int dims3, const void* data, GLuint* out);
/* A texture buffer over a new buffer object holding `size` bytes of `data`;
 * 0 (logged, *buf 0, nothing left behind) when GL could not store them. */
GLuint mesoi_texture_buffer(meso_rt* rt, GLenum format, const void* data, size_t size, GLuint* buf);
/* Bytes per texel of a texture's internal format (the GPU bytes counts:
 * meso_rt.gpu_count). */
size_t mesoi_internal_bytes(GLint internal);
/* An upper bound of the GPU bytes of what resolves to `chunk`s (decoded
 * sizes, 4/3 for mip chains, U16 textures twice where they go up as
 * floats): a level's estimate before its upload (rt_levels.c). */
uint64_t mesoi_gpu_estimate(const meso_rt* rt, const meso_chunk_info* chunk);
/* Around a sequence of uploads: begin saves the texture buffer binding
 * (returns it); end restores it and returns r. Only with check_gl_errors
 * (meso_rt_desc) do they read the GL error queue: begin drains it, end turns
 * an error raised meanwhile into MESO_ERR_GL (logged as "WHAT: GL error").
 * Without, failures are found by mesoi_upload_texels / mesoi_texture_buffer. */
GLint mesoi_upload_begin(meso_rt* rt);
meso_result mesoi_upload_end(meso_rt* rt, GLint prev, meso_result r, const char* what);
/* Overwrites the first `size` bytes of buffer `buf` (animation updates). */
meso_result mesoi_buffer_update(meso_rt* rt, GLuint buf, const void* data, size_t size, const char* what);

/* rt_common.c: one draw, of any kind. prepare (no GL state touched but the
 * viewport query when desc->viewport is unset; fails on a singular object ->
 * clip matrix when `need_inverse`, as the ray casters need it, and on a
 * model matrix that is not a similarity) → begin (under
 * MESO_STATE_RESTORE saves the state meso_rt_draw promises to restore;
 * binds the textures, the counters and `program` with its common uniforms
 * u_mvp, u_inv_mvp, u_viewport, u_light_obj, u_albedo, u_depth_ndc; sets
 * depth test and writes (and desc->depth_func when given), the empty vertex
 * array, for ray casters (`raycast`) front-face culling, and in the depth
 * pass the colour mask off) → the kind's
 * own state, uniforms and draw call → end (reads the counters; restores
 * under MESO_STATE_RESTORE; checks GL errors only when the context was
 * created with check_gl_errors). */
#define MESOI_DRAW_MAX_UNITS 8
/* The shader storage bindings the stats counters take over: the generic one
 * and indexed binding 0 with its range (mesoi_ssbo_save / _restore). */
typedef struct mesoi_ssbo {
    GLint generic, indexed;
    GLint64 start, size;
} mesoi_ssbo;
void mesoi_ssbo_save(meso_rt* rt, mesoi_ssbo* b);
void mesoi_ssbo_restore(meso_rt* rt, const mesoi_ssbo* b);
/* Image unit 0, which the shells' hit image takes over (rt_shell.c;
 * mesoi_image_save / _restore). */
typedef struct mesoi_image_unit {
    GLint name, level, layered, layer, access, format;
} mesoi_image_unit;
void mesoi_image_save(meso_rt* rt, mesoi_image_unit* u);
void mesoi_image_restore(meso_rt* rt, const mesoi_image_unit* u);
typedef struct mesoi_draw {
    double pv[16];              /* proj · view */
    double light_world[3];      /* towards the light, world space (not normalised) */
    int instanced;              /* the per-object values come from the instance buffer (u_instanced) */
    float model[16];            /* object -> world: desc->model, or identity when it is all zero */
    float mvp[16], inv_mvp[16]; /* object -> clip and back (inv_mvp zero when singular) */
    double proj11;              /* |proj[1][1]| */
    double model_scale;         /* the model matrix's uniform scale (length of its first column) */
    int mirrored;               /* the model matrix has a negative determinant: triangles wind the other way */
    GLint viewport[4];
    float light_obj[3], albedo[3];
    float depth_ndc[4];         /* NDC z of the near plane, of a finite point between, of the far plane;
                                   1 for clip depth 0..1 (raycast_common.glsl u_depth_ndc) */
    int reversed;               /* the near plane has the larger depth (MESO_DEPTH_REVERSED) */
    GLenum depth_func;          /* desc->depth_func, or 0 */
    int restore;                /* MESO_STATE_RESTORE */
    int stats; /* the shaders count work (rt->stats_ok and desc->stats) */
    meso_rt_pass pass; /* desc->pass */
    GLboolean prev_color_mask[4]; /* MESO_PASS_DEPTH under MESO_STATE_RESTORE */
    int units;
    GLenum target[MESOI_DRAW_MAX_UNITS];
    GLint prev_bind[MESOI_DRAW_MAX_UNITS];
    GLint prev_program, prev_vao, prev_func, prev_mask, prev_active, prev_cull_mode, prev_front;
    mesoi_ssbo prev_ssbo;
    GLboolean prev_test, prev_cull;
} mesoi_draw;
meso_result mesoi_draw_prepare(meso_rt* rt, const meso_rt_draw_desc* d, int need_inverse, int instanced,
                               mesoi_draw* out);
/* The per-object part of prepare (model, mvp, inv_mvp, model_scale,
 * mirrored, light_obj) from a model matrix (all zero: identity), after
 * prepare set pv and light_world; `index` >= 0 names the instance in the
 * logged reason of a refusal. prepare calls it with desc->model unless
 * `instanced`; instanced draws call it once per instance (rt_instances.c). */
/* Whether a model matrix (all zero: identity) is a similarity, as
 * mesoi_draw_model requires, and whether it mirrors. */
int mesoi_model_similarity(const float* model, int* mirrored);
meso_result mesoi_draw_model(meso_rt* rt, mesoi_draw* s, const float* model, int need_inverse, int64_t index);
void mesoi_draw_begin(meso_rt* rt, mesoi_draw* s, const mesoi_program* program, int raycast, int units,
                      const GLenum* targets, const GLuint* textures);
meso_result mesoi_draw_end(meso_rt* rt, mesoi_draw* s, meso_rt_draw_stats* stats, const char* what);
/* Binds `program` and sets the common uniforms begin sets (for draws of
 * several passes). */
void mesoi_draw_use(meso_rt* rt, const mesoi_draw* s, const mesoi_program* program);
/* The depth function that lets the nearer fragment win under the draw's
 * convention (GL_LESS, or GL_GREATER reversed), and the cleared value of
 * "nothing drawn" (1, or 0 reversed). */
GLenum mesoi_near_func(const mesoi_draw* s);
float mesoi_far_clear(const mesoi_draw* s);

/* rt_common.c: what every shader starts with: the #version line (desktop:
 * "330 core", "430 core" with `stats`; ES: "320 es" and default precisions
 * highp for floats, ints and every sampler type the shaders use), then
 * "#define MESO_STATS 1" with `stats`. A static string. */
const char* mesoi_glsl_prelude(const meso_rt* rt, int stats);
/* An allocation of `count` floats v / 65535 from `count` host-order U16 texels, for contexts without 16-bit normalised textures
 * (ES without GL_EXT_texture_norm16); NULL (logged) when out of memory. */
float* mesoi_unorm16_to_float(meso_rt* rt, const void* texels, size_t count);
/* rt_common.c: the fragment shader's sources between the kind's head
 * ("#version", its #defines) and its own file: "#define MESO_PASS n", the
 * host's shading hook (forward only; "#define MESO_HOOK 1" and "#line 1"
 * before it, a newline after), then `pre` (the kind's common files,
 * pre_count of them) and shaders/pass_out.glsl. Fills src[1 .. pre_count + 4]
 * (src[0] is the caller's head; pass_text is storage for the defines) and
 * returns the number of sources filled, head included; the caller appends
 * its own file. */
int mesoi_frag_sources(const meso_rt* rt, meso_rt_pass pass, const char** src, const char* const* pre,
                       int pre_count, char pass_text[64]);
/* The name a fragment shader is logged under: `file`, and "+ shading hook"
 * when the host's hook is compiled into it (buf holds the text). */
const char* mesoi_frag_name(const meso_rt* rt, meso_rt_pass pass, const char* file, char buf[96]);

/* rt_common.c: shaders. compile: one shader from `count` sources, 0
 * (logged with `name`) on failure; link: links and deletes the two shaders
 * (either may be 0, then both are deleted), 0 (logged) on failure.
 * program_init: links as mesoi_link into *p and looks up every uniform of
 * MESOI_UNIFORMS once; sampler `samplers[i]` is set to unit i (the current
 * program is put back). Returns p->id (0 on failure). */
GLuint mesoi_compile(meso_rt* rt, GLenum type, const char* const* src, int count, const char* name);
GLuint mesoi_link(meso_rt* rt, GLuint vs, GLuint fs, const char* name);
GLuint mesoi_program_init(meso_rt* rt, mesoi_program* p, GLuint vs, GLuint fs, const char* name,
                          const char* const* samplers, int sampler_count);
void mesoi_program_delete(meso_rt* rt, mesoi_program* p);

/* What one kind's program for one draw pass is made of (mesoi_program_build). */
typedef struct mesoi_program_src {
    const char* const* vs; /* vertex shader sources; vs[0] is the head (prelude and defines), shared */
    int vs_count;
    const char* vs_file;   /* the name compile errors are logged under */
    const char* const* pre; /* the kind's common files for the fragment shader */
    int pre_count;
    const char* frag;      /* the kind's fragment file, last */
    const char* frag_file;
    int own_outputs;       /* 1: the fragment file declares its outputs (no pass defines, hook or
                              pass_out.glsl: the slices' offscreen passes) */
    const char* name;      /* the program, in logs */
    const char* const* samplers; /* samplers[i] on unit i */
    int sampler_count;
} mesoi_program_src;
/* Compiles and links `src` into *p for draw pass `pass` (fragment shader:
 * the head, mesoi_frag_sources' pass defines, hook, pre and pass_out.glsl,
 * then the kind's file). Returns p, or NULL (logged) on failure. */
const mesoi_program* mesoi_program_build(meso_rt* rt, mesoi_program* p, meso_rt_pass pass,
                                         const mesoi_program_src* src);
/* 1 when `id` is one of the context's programs. */
int mesoi_program_owned(const meso_rt* rt, GLuint id);

/* rt_common.c: around uploads, the pixel-unpack state they depend on set to
 * GL's defaults (alignment 1, no row length / skips / image height, no
 * unpack buffer bound) and put back after: whatever the host left bound
 * cannot corrupt an upload. */
typedef struct mesoi_unpack {
    GLint saved[8];
    GLint pbo; /* GL_PIXEL_UNPACK_BUFFER_BINDING */
} mesoi_unpack;
void mesoi_unpack_default(meso_rt* rt, mesoi_unpack* u);
void mesoi_unpack_restore(meso_rt* rt, const mesoi_unpack* u);

/* rt_transfer.c: a level's texel and buffer data moved to GL over several
 * meso_rt_stream_upload calls, each under its byte budget. While
 * rt->defer is set, the upload sites (rt_common.c, rt_cells.c, rt_mesh.c)
 * make each texture's and buffer's storage with no data and queue the data
 * (a copy) here; mesoi_transfers_run moves it later, a row band of a
 * texture or a range of a buffer at a time, and builds a texture's mip
 * levels by glGenerateMipmap once its level 0 is whole where the upload
 * would have. */
typedef struct mesoi_transfer {
    GLuint name;
    int buffer;           /* 1: a buffer (data at `offset`), 0: a texture level */
    GLenum target;        /* GL_TEXTURE_2D or GL_TEXTURE_3D */
    GLint level;
    uint32_t dims[3];     /* the level's texels (2D: dims[2] = 1) */
    GLenum format, type;
    int mips;             /* 1: glGenerateMipmap once this level 0 is whole */
    size_t offset;        /* buffer: where the data goes */
    size_t row;           /* bytes per row of texels (buffer: 1) */
    size_t size, done;    /* bytes, and how many have gone up */
    uint8_t* data;        /* owned copy (the context's allocator) */
} mesoi_transfer;
typedef struct mesoi_transfers {
    mesoi_transfer* item;
    uint32_t count, cap, next; /* next: the first not whole */
    int failed;                /* out of memory while queueing */
} mesoi_transfers;
/* Bytes of one texel of (format, type) as handed to GL (components: set). */
size_t mesoi_texel_bytes(GLenum format, GLenum type, int* components);
/* Queue (a copy of) `data` for texture `tex`'s level, whose storage exists. */
void mesoi_defer_texture(meso_rt* rt, GLuint tex, GLenum target, GLint level, const uint32_t dims[3], GLenum format,
                         GLenum type, size_t texel, int mips, const void* data);
/* Queue (a copy of) `size` bytes for buffer `buf` at `offset`. */
void mesoi_defer_buffer(meso_rt* rt, GLuint buf, size_t offset, size_t size, const void* data);
/* Moves queued data until about `budget` bytes have gone (0: all); at least
 * one row or 64 KB. Returns the bytes moved. */
uint64_t mesoi_transfers_run(meso_rt* rt, mesoi_transfers* t, uint64_t budget);
void mesoi_transfers_free(meso_rt* rt, mesoi_transfers* t);
/* Drops the transfers queued from `first` on (their object went). */
void mesoi_transfers_drop(meso_rt* rt, mesoi_transfers* t, uint32_t first);

/* rt_mip_box.c: mip levels on the host (for formats glGenerateMipmap may
 * not take). mip_size: an axis of `n` texels at `level` (halved, rounded
 * down, at least 1); mip_levels: the levels of a full chain for `dims`
 * (2D: dims[2] ignored); mip_box: the level below `fine` (fine_dims, 2D
 * with fine_dims[2] = 1), `components` interleaved values of GL type
 * `type` (GL_UNSIGNED_BYTE, GL_UNSIGNED_SHORT or GL_FLOAT) per texel, into
 * `coarse` (mip_size(fine_dims[k], 1) texels a side). */
uint32_t mesoi_mip_size(uint32_t n, int level);
int mesoi_mip_levels(const uint32_t dims[3], int dims3);
void mesoi_mip_box(const void* fine, const uint32_t fine_dims[3], int components, GLenum type, void* coarse);

/* rt_mesh.c */
/* mesoi_mesh_repack, mesoi_mesh_gpu: rt_mesh_repack.h */
/* The object's MESH chunk into o->vao / o->buffer / index_count (positions
 * at attribute 0, normals at 1, repacked: rt_mesh_repack.c). Cells use it for
 * their base mesh. */
/* colours: also the VCOL at the MESH's lod, when there is one (a mesh or
 * stand-in draw; a cells object's base mesh takes none). */
meso_result mesoi_mesh_upload(meso_rt* rt, meso_file* f, uint32_t object_id, int colours, mesoi_object* o);
/* The same from chunk `ci` (MESH layout: a MESH or a part's PMSH) with the
 * VCOL chunk `vi` (-1: none); `object_id` names it in messages. */
meso_result mesoi_mesh_upload_chunk(meso_rt* rt, meso_file* f, int32_t ci, uint32_t object_id, int32_t vi,
                                    mesoi_object* o);
meso_result mesoi_mesh_prepare(meso_rt* rt, meso_rt_pass pass); /* builds the pass's program */
meso_result mesoi_mesh_draw(meso_rt* rt, mesoi_object* o, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                             uint32_t count);

/* rt_instances.c: per-instance data (shaders/instance.glsl has the texel
 * layout: 0-3 mvp, 4-7 inv_mvp, 8 light_obj + err_scale, 9 prim_base,
 * 10-13 model). upload: for each instance (inst[order[i]], or inst[i]
 * without an order) mesoi_draw_model (refusals name
 * the instance; mixed mirrored and unmirrored instances are refused), the
 * shared texels, then the kind's `fn` for its own; the result into the
 * instance buffer, *tex its texture (to bind at the kind's instance unit).
 * ds->mirrored is left as the instances'. */
#define MESOI_INSTANCE_TEXELS 14
typedef meso_result (*mesoi_instance_fn)(meso_rt* rt, mesoi_object* o, const mesoi_draw* ds,
                                         const meso_rt_draw_desc* d, const meso_rt_instance* in, uint32_t index,
                                         float* texels, void* user);
meso_result mesoi_instances_upload(meso_rt* rt, mesoi_draw* ds, mesoi_object* o, const meso_rt_draw_desc* d,
                                   const meso_rt_instance* inst, const uint32_t* order, uint32_t count,
                                   int need_inverse, mesoi_instance_fn fn, void* user, GLuint* tex);
void mesoi_instances_destroy(meso_rt* rt);
/* The vertex-stage define instance.glsl needs before it. */
#define MESOI_GLSL_VERTEX_STAGE "#define MESO_STAGE_VERTEX 1\n"

/* rt_objects.c */
mesoi_object* mesoi_lookup(const meso_rt* rt, meso_rt_object h);
void mesoi_objects_destroy(meso_rt* rt);
/* rt_objects.c: load level `lod` of object `id` (its record `rec`) into a
 * new slot, drawn as `kind` (the record's, or MESO_OBJECT_MESH for a mesh
 * stand-in). */
meso_result mesoi_load_slot(meso_rt* rt, meso_file* f, const meso_object_record* rec, uint32_t kind, uint16_t lod,
                            meso_rt_object* out);
meso_result mesoi_find_record(meso_rt* rt, meso_file* f, uint32_t id, meso_object_record* rec);
int mesoi_kind_drawn(uint32_t kind); /* a kind this runtime draws */
/* A live slot with no GL resources (a levelled object's own handle). */
meso_result mesoi_empty_slot(meso_rt* rt, const meso_object_record* rec, meso_rt_object* out);
/* rt_levels.c: a levelled object's levels (meso_rt_load_object_levels). */
typedef struct mesoi_levels {
    meso_file* file;
    meso_object_record rec;
    uint32_t count;
    meso_level_info* info;   /* [count], finest first */
    meso_rt_object* slot;    /* [count]: the uploaded level's slot, id 0 when not uploaded */
    uint8_t* failed;         /* [count]: its upload failed (not retried) */
    uint64_t* used;          /* [count]: the frame a draw last used it (rt->frame), for eviction */
    uint64_t* pending;       /* [count]: the frame (rt->frame + 1) its bytes last had not arrived; asked again
                                on a later frame */
    struct meso_rt_request** request; /* [count]: its stream request (rt_stream.c), NULL when none */
    int32_t last_drawn;
    uint64_t bytes_read;
    uint64_t want_frame;     /* the frame want_now/want_lower belong to */
    uint32_t want_now, want_lower; /* the finest level this frame's draws wanted, at the budget's factor and
                                      at the next lower one */
    struct mesoi_parts* parts; /* a mesh object stored with parts (rt_parts.c), else NULL */
    uint64_t parts_frame;      /* the frame (rt->frame + 1) the last pick drew parts */
    int parts_native;          /* they drew with the whole native level (a shell's prisms) */
    int parts_last;            /* the last pick drew parts (meso_rt_parts_state_get) */
    uint64_t* gpu;             /* [2 count]: the level's GPU bytes, measured once uploaded (mesoi_object.gpu_bytes),
                                  until then its estimate; gpu[count + l]: the estimate (level_estimate), no
                                  smaller */
    uint8_t* own_base;         /* [count]: a shell's native level with a base mesh of its own (FORMAT.md §7.10:
                                  its MESH is not level 0's), drawn only by the smooth mapping it was measured
                                  for (rt_levels.c usable) */
} mesoi_levels;
/* rt_parts.c: a levelled mesh object's parts (here for rt_stream.c, which
 * files and uploads part levels as it does levels). */
typedef struct mesoi_parts {
    uint32_t part_count, level_count, edge_count;
    meso_part_level* lv;     /* [level_count], by part then lod */
    uint32_t* first;         /* [part_count + 1]: part p's levels are lv[first[p] .. first[p + 1]) */
    uint32_t* edges;         /* [2 edge_count]: part numbers, 1-based as in the file */
    meso_rt_object* slot;    /* [level_count]: the uploaded part level, id 0 when not */
    uint8_t* failed;         /* [level_count] */
    uint64_t* used;          /* [level_count]: the frame a draw last used it */
    struct meso_rt_request** request; /* [level_count]: its stream request (rt_stream.c), NULL when none */
    uint32_t* want;          /* [part_count]: the level the last pick wanted */
    meso_rt_object* chosen;  /* [part_count]: the slots the last pick drew */
    uint8_t* drawn;          /* [part_count]: the level each drew */
    meso_rt_object parent;   /* the slot picks hand out (kind MESH, no GL resources) */
    uint64_t bytes_wanted;   /* the last pick's wanted part levels' GPU bytes (mesoi_parts.gpu) */
    double fallback_error;   /* where the last pick drew some part coarser than it wanted (its level not
                                uploaded: still arriving, or no room), the largest stated error of the
                                part levels it drew; else -1 */
    uint64_t bytes_read;
    uint64_t pick_frame;     /* the frame (rt->frame + 1) of the last pick */
    /* A shell's parts: each part's lod 0 is its prisms, drawn by the
     * shell's native level `native` (the whole levels' pick), a subset of
     * its prisms: the PTRI list (read once, as lod 0's "upload"). */
    int shell;
    uint32_t* tri;           /* the PTRI list, tri_count entries; NULL before it is read */
    uint64_t* gpu;           /* [2 level_count]: what the part level holds on the GPU, measured once uploaded,
                                until then its estimate; gpu[level_count + i]: the estimate (part_estimate;
                                a shell's prisms: the PTRI list's bytes, held in host memory) */
    uint32_t tri_count;
    meso_rt_object native;
    uint32_t* subset;        /* [tri_count]: the prisms the last pick draws (subset_count), by part */
    uint32_t subset_count;
    uint64_t subset_key;     /* which parts they are (changes re-sort the prisms) */
} mesoi_parts;
/* load: its PRTS table (*out NULL: none); pick: the levels the last
 * mesoi_parts_want chose (each part's for this draw, neighbours within
 * one level), uploads or, with stream requests,
 * requests (MESO_ERR_NOT_FOUND when some part has nothing to draw: draw
 * a whole level instead; MESO_ERR_PENDING, streaming, when every such part
 * waits for a request: draw the best whole level uploaded); *out
 * the slot whose mesh draw draws them (draw). upload: part level i now
 * (rt->prefetch as levels). oldest/evict: the budget's LRU over part
 * levels; bytes: resident part bytes (and the last pick's wanted, and all
 * read). */
meso_result mesoi_parts_load(meso_rt* rt, meso_file* f, const meso_object_record* rec, mesoi_parts** out);
/* want: each part's level for this draw into p->want (nothing read or
 * uploaded), and their bytes; *prisms_wanted 1 when some shell part wants
 * its prisms (their list counted once). A pick draws what the last want
 * chose. finest_patch: the finest level the last pick drew, -1 when some
 * part drew its prisms. */
uint64_t mesoi_parts_want(mesoi_parts* p, const meso_rt_draw_desc* d, const meso_rt_instance* inst, uint32_t count,
                          double tau, double height, int* prisms_wanted);
int mesoi_parts_finest_patch(const mesoi_parts* p);
void mesoi_parts_free(meso_rt* rt, mesoi_parts* p);
meso_result mesoi_parts_pick(meso_rt* rt, mesoi_levels* lv, meso_rt_object native, meso_rt_object* out);
meso_result mesoi_parts_upload(meso_rt* rt, meso_file* f, const meso_object_record* rec, mesoi_parts* p, uint32_t i);
meso_result mesoi_parts_draw(meso_rt* rt, const mesoi_parts* p, const meso_rt_draw_desc* d,
                             const meso_rt_instance* inst, uint32_t count);
int mesoi_parts_oldest(const meso_rt* rt, const mesoi_parts* p, uint64_t* oldest, uint32_t* which);
void mesoi_parts_evict(meso_rt* rt, mesoi_parts* p, uint32_t i);
/* The file bytes of its uploaded part levels (and a shell's prism list);
 * *read gets every byte read for them. */
uint64_t mesoi_parts_bytes(const mesoi_parts* p, uint64_t* read);
/* The GPU bytes its uploaded part levels hold (and a shell's prism list);
 * *estimated gets what they were estimated at before upload. */
uint64_t mesoi_parts_gpu(const mesoi_parts* p, uint64_t* estimated);
/* Whether the last pick drew some part coarser than its lod 0, and every
 * part at the level it wanted (a shell whose parts are still arriving
 * draws its whole native level, which is finer). */
int mesoi_parts_coarse(const mesoi_parts* p);
/* rt_levels.c: pixels `error` covers for bounds lo..hi drawn with `model`
 * (the LOD rule, rt_levels.c); evict_one: the least recently used level or
 * part level no draw of this frame used (not an object's coarsest); 0 when
 * none. */
double mesoi_projected_px(double error, const float lo[3], const float hi[3], const float* model,
                          const meso_rt_draw_desc* d, double height);
int mesoi_evict_one(meso_rt* rt);
/* Upload level l now (reading the file, or the stream request being
 * uploaded, rt->prefetch); MESO_ERR_PENDING when its bytes have not arrived
 * (not remembered), another error is remembered in lv->failed. */
meso_result mesoi_levels_upload(meso_rt* rt, mesoi_levels* lv, uint32_t l);
/* mesoi_levels_upload in two steps: the load into *slot (its GPU bytes
 * counted resident, a failure remembered), and making it the level's. */
meso_result mesoi_levels_load(meso_rt* rt, mesoi_levels* lv, uint32_t l, meso_rt_object* slot, uint64_t* gpu);
void mesoi_levels_publish(mesoi_levels* lv, uint32_t l, meso_rt_object slot, uint64_t gpu);
/* Room for `bytes` more under the memory budget (a level or a part level),
 * evicting levels this frame does not use; 0 when it cannot be made. */
int mesoi_make_room(meso_rt* rt, uint64_t bytes);
/* A public draw call of h begins: what its picks draw in parts is
 * reported from here on (meso_rt_parts_state_get). */
void mesoi_levels_draw_begin(meso_rt* rt, meso_rt_object h);
/* rt_levels.c: the level of a levelled object `o` the draw picks (uploaded
 * on first use); *out is `o` itself for a plain object. `o` may move (the
 * slot table can grow): use *out. */
meso_result mesoi_levels_pick(meso_rt* rt, meso_rt_object h, const meso_rt_draw_desc* d, const meso_rt_instance* inst,
                              uint32_t count, meso_rt_object* out);
/* rt_levels.c: per instance, the level it would draw alone (level[i]);
 * returns how many levels differ, 0 when the object has no levels (or more
 * than 32), the draw asks for the finest, or count < 2 (one level for the
 * draw). */
uint32_t mesoi_levels_per_instance(meso_rt* rt, meso_rt_object h, const meso_rt_draw_desc* d,
                                   const meso_rt_instance* inst, uint32_t count, uint8_t* level);
void mesoi_levels_release(meso_rt* rt, mesoi_object* o);
/* rt_stream.c: file a request for level l (once); detach a released
 * object's requests (its parts' too); free every request (meso_rt_destroy); the chunk
 * `ci` of the request being uploaded (rt->prefetch), handed over (the
 * caller frees it with mesoi_rt_free); NULL when it has none. */
meso_result mesoi_stream_request(meso_rt* rt, mesoi_levels* lv, uint32_t l);
/* The same for level i of lv->parts (its lv[i]). */
meso_result mesoi_stream_request_part(meso_rt* rt, mesoi_levels* lv, uint32_t i);
void mesoi_stream_detach(meso_rt* rt, mesoi_levels* lv);
void mesoi_stream_destroy(meso_rt* rt);
void* mesoi_stream_take_chunk(meso_rt* rt, int32_t ci);
/* The MESH-layout chunk `ci` (MESH, PMSH) of the request being uploaded,
 * parsed and repacked off the GL thread (mesoi_mesh_repack), handed over
 * with *out; NULL when it has none. */
void* mesoi_stream_take_mesh(meso_rt* rt, int32_t ci, mesoi_mesh_gpu* out);
/* The CELLS check the request being uploaded ran (its TILE and MEMB copies,
 * the file's allocator's); 0 when there is none. */
int mesoi_stream_take_cells(meso_rt* rt, uint8_t** tile, uint8_t** memb, int* id_bits);

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
