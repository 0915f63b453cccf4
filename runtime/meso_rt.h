/*
 * meso_rt.h — libmeso, the runtime: stream a .meso file and ray cast it with
 * OpenGL into the host's framebuffer and depth buffer.
 *
 * C11. Depends on nothing but OpenGL (3.3 core or newer, or OpenGL ES 3.2;
 * meso_rt_create tells them apart) and what the host passes in: its GL loader, and optionally an allocator, a logger and read
 * callbacks. No global state: every call takes a meso_rt context, and several
 * contexts may live side by side (one per GL context).
 *
 *     meso_rt* rt = NULL;
 *     if (meso_rt_create(&(meso_rt_desc){ .gl_get_proc_address = glfwGetProcAddress }, &rt) != MESO_OK)
 *         ...;   // the logger (if any) said why
 *     ...
 *     meso_rt_destroy(rt);
 *
 * The host makes its GL context current before every meso_rt_* call and
 * keeps it current; the runtime never creates windows or contexts.
 */
#ifndef MESO_RT_H
#define MESO_RT_H

#include <stddef.h>
#include <stdint.h>

#include "meso_file.h" /* meso_result, meso_allocator, meso_io, meso_error */

#ifdef __cplusplus
extern "C" {
#endif

/* >>logging --------------------------------------------------------------- */

typedef enum meso_log_level {
    MESO_LOG_ERROR = 0,
    MESO_LOG_WARNING,
    MESO_LOG_INFO,
    MESO_LOG_LEVEL_COUNT
} meso_log_level;

/* Numbered log items: tests assert on them, hosts may filter by them. */
#define MESO_LOG_ITEMS(X)                                                           \
    X(OK, "no error")                                                               \
    X(GL_ENTRY_POINT_MISSING, "a required OpenGL function was not found")          \
    X(GL_VERSION_TOO_OLD, "OpenGL 3.3 core or newer, or OpenGL ES 3.2, is required") \
    X(GL_ERROR, "an OpenGL call raised an error")                                   \
    X(SHADER_COMPILE_FAILED, "a shader failed to compile")                          \
    X(PROGRAM_LINK_FAILED, "a shader program failed to link")                       \
    X(OUT_OF_MEMORY, "memory allocation failed")                                    \
    X(FILE_OPEN_FAILED, "the .meso file could not be opened")                       \
    X(CHUNK_READ_FAILED, "a chunk could not be read")                               \
    X(OBJECT_NOT_FOUND, "the file has no drawable object with that id")             \
    X(INVALID_ARGUMENT, "an argument violates the API contract")                    \
    X(CONTEXT_CREATED, "runtime context created")

typedef enum meso_log_item {
#define MESO_X_ENUM(id, text) MESO_LOGITEM_##id,
    MESO_LOG_ITEMS(MESO_X_ENUM)
#undef MESO_X_ENUM
        MESO_LOGITEM_COUNT
} meso_log_item;

/* Static description of an item, never NULL. */
MESO_API const char* meso_log_item_string(meso_log_item item);

/* `message` is the item's detail (e.g. the missing function's name), or NULL. */
typedef void (*meso_log_fn)(void* user, meso_log_level level, meso_log_item item, const char* message);

/* >>context --------------------------------------------------------------- */

typedef void (*meso_gl_fn)(void);
typedef meso_gl_fn (*meso_gl_get_proc_fn)(const char* name);

/* Who owns the GL state around meso_rt_draw (see meso_rt_draw for the list
 * of what a draw changes). */
typedef enum meso_rt_state_policy {
    MESO_STATE_RESTORE = 0, /* every draw queries the state it changes and puts it back: drop-in, a few
                               glGet calls per draw */
    MESO_STATE_HOST_OWNS    /* a draw queries nothing and restores nothing: it sets what it needs and
                               leaves it set; the host sets whatever it relies on before its own draws
                               (engines with their own state cache) */
} meso_rt_state_policy;

/* How the textures that give a shell its appearance are filtered
 * (meso_rt_desc.texture_filter): height fields and volumes where they shade
 * (normals, the occlusion term) and colour maps, of shells and of relief
 * frusta. The intersection search always reads the finest level (the
 * distance maps bound that level only; the frusta march samples level 0).
 * Cells objects have no texture to prefilter (a voxel's colour and normal
 * are its cell's): under MESO_FILTER_MIPMAP a draw may ask for several
 * rays across far pixels instead (meso_rt_cells_draw.footprint_rays,
 * runtime/shaders/cells_frag.glsl ">>footprint"). */
typedef enum meso_texture_filter {
    MESO_FILTER_MIPMAP = 0, /* a full mip chain built at upload; shading samples the level of the pixel's
                               footprint on the surface (trilinear), and the forward pass's built-in
                               shading averages up to 4 x 4 taps over the footprint, so far objects do not
                               shimmer */
    MESO_FILTER_LEVEL0,     /* one level, bilinear: what the exact reference computes, and what the runtime
                               did before mip levels (for comparisons; aliases when minified) */
    MESO_FILTER_COUNT
} meso_texture_filter;

typedef struct meso_rt_desc {
    meso_gl_get_proc_fn gl_get_proc_address; /* required: glfwGetProcAddress, eglGetProcAddress, ... */
    meso_allocator allocator;                /* optional (default malloc/free) */
    meso_log_fn log_fn;                      /* optional: silent without one */
    void* log_user;
    meso_rt_state_policy state_policy;       /* [MESO_STATE_RESTORE] */
    int check_gl_errors;  /* 1: read the GL error queue after uploads and draws, log what it holds
                             (GL_ERROR) and return MESO_ERR_GL. This takes errors the host raised
                             before the call too, so it is for debugging. 0: the runtime never calls
                             glGetError; failed uploads are still found (from the texture or buffer
                             GL made) and refused [0] */
    int prepare;          /* 1: meso_rt_prepare(rt, 0) inside create, so no draw compiles a shader [0] */
    meso_texture_filter texture_filter; /* appearance textures: mip levels or level 0 only; fixed for the
                                           context's life (objects upload their levels at load)
                                           [MESO_FILTER_MIPMAP] */
    /* Shading hook: GLSL 3.30 source (copied at create) that defines
     *
     *     vec3 meso_shade(vec3 albedo, vec3 n_world, vec3 p_world, vec3 v_world);
     *
     * Every MESO_PASS_FORWARD fragment shader then returns its value as the
     * pixel's colour (a = 1) in place of the built-in Lambert term. Arguments,
     * all world space: albedo = the material colour times the built-in
     * occlusion factor (what MESO_PASS_GBUFFER writes as rgb * a); n_world the
     * unit shading normal, facing the viewer (the G-buffer's normal); p_world
     * the hit point; v_world the unit direction from the hit towards the eye.
     * Called once per fragment that hits; for cells in REFLECT / REFRACT modes
     * at every traced hit (the environment terms are mixed in after). Not
     * applied to MESO_SHELL_SEGMENT_ONLY (a diagnostic colour) nor to the
     * two-pass slice variants (their colour is the built-in).
     * The snippet is compiled after the runtime's prelude — "#version 330
     * core" ("430 core" for the work-counting variants), or on OpenGL ES
     * "#version 320 es" with highp default precisions — its #defines and a
     * "#line 1", so compile errors give the snippet's own line numbers; all
     * other runtime code follows it. It may rely on built-ins common to
     * GLSL 3.30 core and GLSL ES 3.20 (write it to both if the host runs
     * both: ES has no implicit int-to-float conversions) and its own
     * declarations only. The runtime's shaders define
     * many unprefixed names (shade, solid, occlusion, ...): prefix every global
     * name of the snippet but meso_shade with `hook_`.
     * Data from the host: constants in the snippet, or one uniform block it
     * declares as `layout(std140) uniform MesoHook { ... };`, which every
     * program is linked to uniform buffer binding point shading_hook_binding:
     * the host binds its buffer there (glBindBufferBase(GL_UNIFORM_BUFFER,
     * binding, buf)) before drawing; libmeso never touches that binding. Plain
     * `uniform` variables cannot be set through libmeso.
     * Errors: a snippet that does not compile alone (checked at create with a
     * one-line shader calling meso_shade) or clashes with the mesh shader
     * (built at create) fails meso_rt_create with MESO_ERR_GL; one that
     * clashes with another kind's shader fails that kind's first draw or
     * meso_rt_prepare with MESO_ERR_GL. Each is logged as
     * SHADER_COMPILE_FAILED naming "shading hook". NULL: the built-in
     * shading [NULL] */
    const char* shading_hook;
    uint32_t shading_hook_binding; /* uniform buffer binding point of the hook's MesoHook block [0] */
    /* Levels of detail (meso_rt_load_object_levels): the GPU bytes every
     * levelled object's uploaded levels may hold together: the texels of
     * their textures (every mip level, at the internal format's size) and
     * the bytes of their buffers, as libmeso creates them (a MESH holds
     * 12 bytes a vertex of positions, 4 of normals and 2 an index, 4 from
     * 65536 vertices, each array from a multiple of 16; then its vertex
     * colours, if drawn with any; frame resources
     * shared by every object, shaders and the host's memory are not
     * counted). A level not uploaded yet counts as an estimate no smaller
     * (4/3 of its chunks' decoded bytes, the mip chain's share; twice that
     * for 16-bit textures that go up as floats), replaced by what it holds
     * once uploaded (meso_rt_levels_state). A draw that would
     * go over evicts levels no draw of the current frame used, least
     * recently used first, and otherwise draws a level already uploaded;
     * meso_rt_frame_end raises the pixel error of every draw by a common
     * factor while the frame's levels do not fit, and lowers it again once
     * the levels of the lower factor would fit. Each object's coarsest
     * level always stays. 0: no budget [0] */
    uint64_t memory_budget;
    /* Streaming of levelled objects (meso_rt_stream_take). 0: a draw that
     * picks a level not uploaded yet reads, decodes and uploads it itself,
     * on the calling (GL) thread. 1: it only requests it and draws the best
     * level uploaded (nothing while none is); the host runs the requests'
     * reads and decodes on any thread and uploads them at a byte budget per
     * frame, so no draw waits on the file [0] */
    uint32_t stream_requests;
} meso_rt_desc;

typedef struct meso_rt meso_rt;

/* Create a context: loads every GL entry point the runtime uses through
 * desc->gl_get_proc_address and checks the context is OpenGL 3.3 core or
 * newer, or OpenGL ES 3.2 or newer (GL_VERSION starting "OpenGL ES"). The
 * same shaders run on both, behind a version and precision prelude (ES:
 * "#version 320 es", highp floats, ints and samplers). On ES:
 *  - 16-bit normalised textures (U16 texture functions and distance maps,
 *    cells' NRMM normals) need GL_EXT_texture_norm16. Without it they are
 *    converted on the CPU to 32-bit floats (v / 65535: no precision lost)
 *    where the texture is sampled nearest or GL_OES_texture_float_linear
 *    is present, else (U16 texture functions, which are filtered linearly)
 *    to 16-bit floats, which keep 11 significant bits: an error up to
 *    2^-12 relative, about 2.4e-4 near 1, where 16 bits resolve 1.5e-5.
 *  - draw stats need fragment shader storage blocks
 *    (GL_MAX_FRAGMENT_SHADER_STORAGE_BLOCKS > 0), else `supported` is 0.
 * Fails with MESO_ERR_GL (logging GL_ENTRY_POINT_MISSING with the
 * function's name, or GL_VERSION_TOO_OLD), MESO_ERR_OUT_OF_MEMORY or
 * MESO_ERR_INVALID_ARG. On success *out must be destroyed. */
MESO_API meso_result meso_rt_create(const meso_rt_desc* desc, meso_rt** out);
/* Release every GL object and all memory of the context. NULL is allowed. */
MESO_API void meso_rt_destroy(meso_rt* rt);

/* The context's GL version as major*10+minor (e.g. 45; 32 for ES 3.2). */
MESO_API int meso_rt_gl_version(const meso_rt* rt);
/* 1 when the context is OpenGL ES, 0 for desktop OpenGL (and for NULL). */
MESO_API int meso_rt_gl_is_es(const meso_rt* rt);

/* Shader pre-warm: compile and link every program meso_rt_draw may use now,
 * so that no draw compiles one (a first-draw hitch of tens of milliseconds
 * per program on a software rasteriser). Flags: MESO_PREPARE_STATS also the
 * work-counting variants (OpenGL 4.3, or ES with fragment shader storage;
 * elsewhere ignored); MESO_PREPARE_ALL_PASSES also the depth and G-buffer
 * variants (meso_rt_pass). Programs already built are
 * kept. MESO_ERR_GL (logged) when one fails to build. The GL state is left
 * as it was. */
#define MESO_PREPARE_STATS 1u
#define MESO_PREPARE_ALL_PASSES 2u /* also the MESO_PASS_DEPTH and MESO_PASS_GBUFFER variants of every
                                      kind (without it: MESO_PASS_FORWARD only) */
MESO_API meso_result meso_rt_prepare(meso_rt* rt, uint32_t flags);

/* >>objects --------------------------------------------------------------- */

/* Handle of an uploaded object; id 0 is never valid. A released handle is
 * detected (generation counter) and refused with MESO_ERR_INVALID_ARG. */
typedef struct meso_rt_object {
    uint32_t id;
} meso_rt_object;

/* Stream one object from an open file and upload it: only that object's
 * chunks are read (through whatever reader the file was opened with: path,
 * mmap, memory or the host's meso_io callbacks). Supported kinds:
 * MESO_OBJECT_MESH (drawn as the shaded mesh), MESO_OBJECT_SHELL (ray cast
 * through its texture function, FORMAT.md §7.2), MESO_OBJECT_FRUSTA
 * (relief-mapped conical frusta and balls, ray cast analytically; FRUS, FSEG
 * and SKEL are required, BALL and RELF optional) and MESO_OBJECT_CELLS
 * (tiled voxel cells ray traced from the base mesh; the chunks of the level
 * loaded are checked with meso_file_check_cells_level first, a bad file is
 * refused with the check's message logged). Other kinds give
 * MESO_ERR_UNSUPPORTED. Encoded chunks (Draco) need a decoder in the
 * meso_open_desc the file was opened with. On failure nothing is uploaded
 * and out->id is 0. `file` may be closed after this returns. */
MESO_API meso_result meso_rt_load_object(meso_rt* rt, meso_file* file, uint32_t object_id, meso_rt_object* out);
/* Levels of detail (FORMAT.md §7.10). Like meso_rt_load_object, but the
 * object keeps every level the file stores for it and each draw picks one:
 * the coarsest whose error, projected at the level's nearest bound, is at
 * most the draw's `pixel_error` (meso_rt_draw_desc). Only the coarsest
 * level is uploaded here; a finer one is read from `file` and uploaded the
 * first time a draw picks it (or, with meso_rt_desc.stream_requests, is
 * requested: >>streaming below). While a level cannot be had (bytes a
 * stream has not delivered yet, MESO_IO_PENDING: asked again on a later
 * frame; a damaged chunk: logged once, not retried) the draw takes the
 * finest coarser level it can read, else the nearest finer one uploaded
 * before, else draws nothing; so `file` must stay open until the object
 * is released and its taken stream requests are given back. A mesh stand-in
 * level (form MESO_LEVEL_MESH) is drawn as a mesh. A file without levels
 * gives one level (the object as meso_rt_load_object loads it). The
 * kind-specific calls (meso_rt_shell_*, meso_rt_frusta_*) do not apply to
 * such an object (MESO_ERR_INVALID_ARG or empty answers). */
MESO_API meso_result meso_rt_load_object_levels(meso_rt* rt, meso_file* file, uint32_t object_id,
                                                meso_rt_object* out);

/* What a levelled object holds: its level count, which are uploaded, the
 * level its last draw used, the file bytes of the uploaded levels'
 * chunks and what they hold on the GPU. A plain object reports one level,
 * uploaded and drawn. */
typedef struct meso_rt_levels_state {
    uint32_t level_count;
    uint32_t resident_mask;   /* bit L: level L is uploaded (levels >= 32 are not reported) */
    int32_t last_drawn;       /* lod of the last draw, -1 before the first (drawn in parts: the finest
                                 part level drawn) */
    uint64_t bytes_resident;  /* sum of the uploaded levels' chunk bytes (meso_level_info.bytes) */
    uint64_t bytes_read;      /* every byte read from the file for this object, uploads that failed included
                                 (reads that found their bytes not arrived yet are not counted) */
    uint64_t gpu_bytes_resident;  /* what the uploaded levels' (and parts') textures and buffers hold on the
                                     GPU: texels (every mip level) and buffer bytes, as created; the unit
                                     of meso_rt_desc.memory_budget */
    uint64_t gpu_bytes_estimated; /* the uploaded levels' estimates before upload (no smaller than what they
                                     hold: what the budget makes room for) */
} meso_rt_levels_state;
MESO_API meso_result meso_rt_levels_state_get(const meso_rt* rt, meso_rt_object obj, meso_rt_levels_state* out);
/* A levelled mesh object stored with parts (FORMAT.md §7.11) draws its
 * level 0 part by part: each part at the coarsest of its own levels whose
 * projected error is at most the pixel error, neighbouring parts within
 * one level of each other (never a crack: the bake keeps part borders
 * fixed at every level). A levelled shell stored with parts does the same
 * where it draws a native level, smooth or curved, in a context that can
 * reject hull fragments (meso_rt_shell_draw.no_hull_reject says which;
 * the knob itself does not matter here): a part at lod 0
 * draws its prisms with that level, a coarser one its stand-in patch (a
 * mesh), which meets the prisms within its error. Where the whole object
 * would draw a coarser level (a shell: or where every part wants its
 * patch), the parts draw instead when their own levels hold fewer bytes
 * than that level. Its levels state counts the parts' bytes too.
 * This reports the level each part drew in the object's last draw
 * (levels[part - 1], up to `cap`; MESO_RT_PART_NOT_DRAWN for every part
 * when that draw drew a whole level, or before the first draw) and
 * *part_count (0: the object has no parts; the parts table is read with
 * the levels table, by meso_rt_load_object_levels). A whole level draws
 * instead of parts that had to fall back to coarser levels than they
 * wanted (streamed, still arriving) where it has a smaller error than the
 * worst of them. Under
 * meso_rt_desc.stream_requests part levels are requested as levels are
 * (>>streaming); until every part has a level uploaded the object draws
 * its best whole level uploaded, and never asks for its whole level 0. */
#define MESO_RT_PART_NOT_DRAWN 255
MESO_API meso_result meso_rt_parts_state_get(const meso_rt* rt, meso_rt_object obj, uint8_t* levels, uint32_t cap,
                                             uint32_t* part_count);

/* End of a frame, for the memory budget (meso_rt_desc.memory_budget):
 * adjusts the factor every draw's pixel error is multiplied by (x 1.25
 * while the levels the frame's draws wanted exceed the budget; / 1.1,
 * down to 1, when the levels they would want at the lower factor fit) and
 * evicts levels not used this frame while over budget. The factor only
 * falls when the lower one is known to fit, so under a static camera it
 * settles and does not oscillate. Without a budget it only counts frames. */
MESO_API void meso_rt_frame_end(meso_rt* rt);
typedef struct meso_rt_budget_state {
    uint64_t budget;          /* meso_rt_desc.memory_budget */
    uint64_t bytes_resident;  /* GPU bytes, over every levelled object (the budget's unit) */
    uint64_t bytes_wanted;    /* GPU bytes of the levels the last frame's draws wanted (estimated for those not
                                 uploaded yet: meso_rt_desc.memory_budget) */
    double pixel_error_scale; /* the factor, >= 1 */
    uint64_t frames;          /* meso_rt_frame_end calls */
    uint64_t evictions;       /* levels evicted so far */
} meso_rt_budget_state;
MESO_API void meso_rt_budget_state_get(const meso_rt* rt, meso_rt_budget_state* out);

/* >>streaming ------------------------------------------------------------- */

/* Levelled objects in a file that is still arriving. A meso_io reader
 * answers MESO_IO_PENDING for bytes it has not received; the level is then
 * asked for again on a later frame (a failure of any other kind is logged
 * once and not retried). meso_rt_load_object_levels succeeds once the
 * object's record and level table (and a mesh object's parts table, which
 * the writer puts next to it) have arrived, and the object draws as
 * soon as its coarsest level has: until then its draws draw nothing and
 * return MESO_OK (meso_rt_levels_state.resident_mask is 0).
 *
 * With meso_rt_desc.stream_requests = 1, no draw reads the file. A draw
 * that picks a level (or a part level) not uploaded yet files a request
 * for it (one per level) and draws the best uploaded level meanwhile. The host moves the
 * requests through three steps each frame:
 *
 *   n = meso_rt_stream_take(rt, reqs, 16);          GL thread
 *   for each: meso_rt_stream_run(reqs[i]);           any thread, in parallel
 *   meso_rt_stream_give(rt, reqs, n);                GL thread
 *   meso_rt_stream_upload(rt, 4 << 20);              GL thread, bytes per frame
 *
 * `run` reads, checks (CRC, the kind's checks) and decodes the level's
 * chunks into memory; it touches neither GL nor the context. Run on other
 * threads, it calls the context's allocator, the file's allocator and the
 * file's decoders (meso_open_desc) there, so those must then be
 * thread-safe, as malloc and the Draco adapter are.
 * `upload` turns decoded levels into GL objects, oldest first, until
 * `max_bytes` bytes are uploaded. A level larger than what is left of the
 * call's budget goes up over several calls: its textures and buffers are
 * made at once and their data follows in pieces (bands of texel rows,
 * ranges of a buffer; mip levels are built once a texture's level 0 is
 * whole), and the level is drawn only once all of it is up. A part level
 * (a mesh's or a shell's) goes up whole.
 * A request whose object is released meanwhile is freed when given back.
 * Every taken request must be given back before meso_rt_destroy. */
typedef struct meso_rt_request meso_rt_request;
/* Up to `max` requests no one has taken, the oldest first; returns how many. */
MESO_API uint32_t meso_rt_stream_take(meso_rt* rt, meso_rt_request** out, uint32_t max);
/* Reads and decodes one taken request. MESO_OK; MESO_ERR_PENDING when its
 * bytes have not all arrived (give it back: it is taken again later);
 * another error when they are bad (given back, the level is marked failed
 * and not asked for again). */
MESO_API meso_result meso_rt_stream_run(meso_rt_request* req);
/* Gives taken requests back, run or not (a request not run is taken again). */
MESO_API void meso_rt_stream_give(meso_rt* rt, meso_rt_request* const* reqs, uint32_t n);
/* Uploads decoded requests until `max_bytes` bytes are uploaded (0: all):
 * a whole level or part level counts its chunk bytes, a piece of a level
 * going up over several calls the bytes it hands to GL; every call moves
 * at least one texel row or 64 KB of a buffer, so the last piece may pass
 * the budget by that much. Returns the bytes uploaded. A level with no room under
 * meso_rt_desc.memory_budget stays decoded (host memory) and is tried again
 * on later calls while draws still want it; it is dropped once they want a
 * coarser level or stop drawing the object. */
MESO_API uint64_t meso_rt_stream_upload(meso_rt* rt, uint64_t max_bytes);
/* Requests waiting to be taken, taken, and decoded waiting for upload. */
typedef struct meso_rt_stream_state {
    uint32_t waiting, taken, decoded; /* decoded: waiting for upload, or part way up */
    uint64_t uploads;        /* levels uploaded through requests so far */
} meso_rt_stream_state;
MESO_API void meso_rt_stream_state_get(const meso_rt* rt, meso_rt_stream_state* out);

/* Free the object's GL resources. Stale or zero handles are ignored. */
MESO_API void meso_rt_release_object(meso_rt* rt, meso_rt_object obj);
/* Object-space bounds from the file's OBJT record. */
MESO_API meso_result meso_rt_object_bounds(const meso_rt* rt, meso_rt_object obj, float lo[3], float hi[3]);

/* Shell techniques: ray casting (papers/smooth-and-curved-shell-mapping.md), or slices. */
typedef enum meso_shell_technique {
    MESO_SHELL_SMOOTH = 0,  /* §3.1/§4: Φ along interpolated directors, corrected ray-path sampling */
    MESO_SHELL_CURVED,      /* §3.2/§4.5: Coons-patch curved shells, continuous across edges and only
                               approximately tangent-continuous (G1): the crease between two prisms
                               is a fraction of the flat shell's, not zero (tests/reference/test_shell_map.c
                               measures 0.065° against 12.8° on a sphere-like pair, 4.1° against 24.6°
                               on a sharply bent one) */
    MESO_SHELL_TETRA,       /* the baseline: each prism as three tetrahedra, linear in each */
    MESO_SHELL_SEGMENT_ONLY, /* §4.2 only: entry/exit in texture space, no sampling (Table 1's first column) */
    MESO_SHELL_SLICES,       /* not a ray caster: slice polygons through each prism and an alpha test at the
                                isosurface (papers/volume-textures-lp-averaged-shells.md §5; runtime/rt_slices.c),
                                knobs `slices` and `slice_interp` */
    MESO_SHELL_TECHNIQUE_COUNT
} meso_shell_technique;

/* How MESO_SHELL_SLICES finds the normal and depth between two slices
 * (papers/volume-textures-lp-averaged-shells.md §5, Figures 11-12). */
typedef enum meso_slice_interp {
    MESO_SLICE_TEXCOORD = 0, /* the paper's two passes: texture coordinates of the last slice outside and the
                                first inside interpolated to the α = ½ crossing; gradient looked up there */
    MESO_SLICE_NORMAL,       /* the same two passes, the normals at the two slices interpolated instead */
    MESO_SLICE_NONE,         /* one pass: the first slice inside, its own normal and depth */
    MESO_SLICE_INTERP_COUNT
} meso_slice_interp;

/* Which way MESO_SHELL_SLICES cuts each prism (papers/volume-textures-lp-averaged-shells.md §5:
 * "slices are oriented in the direction closest to the view direction", Figure 11). */
typedef enum meso_slice_axis {
    MESO_SLICE_AXIS_VIEW = 0, /* per prism and draw, the family of slices the view ray through the prism's
                                 centre crosses most densely: the levels w = m/(slices-1), or the planes of
                                 constant barycentric λ_i = m/slices, one family per corner (runtime/shaders/
                                 shell_slices_vert.glsl); at grazing views the in-plane families take over */
    MESO_SLICE_AXIS_LEVELS,   /* always the levels (cheaper: 3 vertices a slice; blurs at grazing views) */
    MESO_SLICE_AXIS_COUNT
} meso_slice_axis;

/* How cells objects are ray traced (papers/cell-based-object-representation.md §3.2). */
typedef enum meso_cells_mode {
    MESO_CELLS_FIRST_HIT = 0, /* §3.2.2: the first inside cell's boundary, shaded */
    MESO_CELLS_REFLECT,       /* §3.2.3: plus specular self-reflection, then the environment */
    MESO_CELLS_REFRACT        /* §3.2.4: refraction through the cells, then the environment */
} meso_cells_mode;

/* Work counted by the shaders during one draw (needs OpenGL 4.3, or ES
 * with fragment shader storage blocks, for the counters; on other
 * contexts, and for MESH objects, `supported` is 0 and
 * the counts are 0). */
typedef struct meso_rt_draw_stats {
    int supported;
    uint64_t fragments; /* ray-casting fragment invocations */
    uint64_t steps;     /* texture samples along rays (march + refinement) */
    uint64_t hits;      /* fragments that found the surface */
    uint64_t rejected;  /* shells: hull fragment invocations stopped before ray casting, their hull entry
                           behind a hit the draw found already at their pixel (not in `fragments`; see
                           meso_rt_shell_draw.no_hull_reject) */
} meso_rt_draw_stats;

/* The knobs of each object kind: meso_rt_draw reads only the struct of the
 * object's kind, so one desc may carry all three and draw any object. Every
 * field's zero means the default in brackets. */

/* MESO_OBJECT_SHELL (FORMAT.md §7.2, papers/smooth-and-curved-shell-mapping.md §4). */
typedef struct meso_rt_shell_draw {
    meso_shell_technique technique; /* [MESO_SHELL_SMOOTH] */
    float error_px;      /* image-space error bound of the corrected ray path, pixels; a quarter of it is
                            the smallest step near surfaces [1] */
    int max_steps;       /* march steps per prism and pixel; out of steps, the surface is taken to be at
                            the last sample (drawn too high, never a hole) [256] */
    int bisection_steps; /* refinement steps once the surface is bracketed [4] */
    int segment_steps;   /* bisection steps on w for the ray segment (§4.2) [12] */
    float uv_scale;      /* multiplies the baked texture coordinates (tiling) [1] */
    int no_distance_map; /* 1: march at fixed_step instead of sphere tracing the distance map [0] */
    float fixed_step;    /* texture-space step without a distance map [1/256] */
    int no_hull_reject;  /* 1: every hull fragment ray casts, as before issue 14 (for comparison); 0: where
                            the context can (rt_shell.c: OpenGL 4.2 image atomics and a texture clear, or
                            ES 3.2 with EXT_clear_texture) and the depth function lets the nearer fragment
                            win, prisms are drawn roughly front to back by their entry faces and a fragment
                            whose entry lies behind a hit the draw found at its pixel stops at once.
                            The depth function is desc.depth_func, else the host's under
                            MESO_STATE_RESTORE, else GL_LESS (GL_GREATER reversed) — also for the items of
                            meso_rt_draw_list, which draw as HOST_OWNS: a list under another depth function
                            sets depth_func or this. The hit stored per pixel is per pixel, not per sample:
                            with MSAA or stencil z-fail operations, set this [0] */
    int no_prism_walk;   /* MESO_SHELL_SMOOTH with hull rejection: 1: every prism rasterises all its entry
                            faces, as before (for comparison); 0: sides two prisms share are not
                            rasterised, and a ray that leaves a prism through one goes on in the
                            neighbour (rt_prism_walk.c), so a pixel gets a fragment for each time its ray
                            enters the shell, not for each prism it crosses [0] */
    int slices;          /* MESO_SHELL_SLICES: slice polygons per prism (along the chosen family: levels
                            w = m / (slices - 1), or λ_i = m / slices), 2..1024 [16] */
    meso_slice_interp slice_interp; /* MESO_SHELL_SLICES [MESO_SLICE_TEXCOORD] */
    meso_slice_axis slice_axis;     /* MESO_SHELL_SLICES [MESO_SLICE_AXIS_VIEW] */
} meso_rt_shell_draw;

/* MESO_OBJECT_FRUSTA (papers/relief-mapped-conical-frusta.md §3: the relief
 * march is uniform sampling plus bisection). */
typedef struct meso_rt_frusta_draw {
    int relief_steps;    /* uniform samples per relief march, over the ray's part inside the relief layer
                            before (and, leaving it, after) the solid core; more catches thinner bumps at
                            grazing angles [64]. A native level whose relief map is narrower than level
                            0's takes as many per texel: relief_steps x its width / level 0's, rounded
                            up, at least 8 (or relief_steps, if fewer) */
    int bisection_steps; /* refinement steps once the surface is bracketed [4] */
} meso_rt_frusta_draw;

/* MESO_OBJECT_CELLS (papers/cell-based-object-representation.md §3.2;
 * runtime/reference/cell_reference.h states the rules exactly). */
typedef struct meso_rt_cells_draw {
    meso_cells_mode mode; /* [MESO_CELLS_FIRST_HIT] */
    int bounces;          /* reflection: rays traced after the first hit (0 = environment mapping at the
                             first hit); refraction: exits and re-entries traced after it; 0..8 [0] */
    float step;           /* 0: exact voxel traversal, never misses a voxel; > 0: the thesis's linear
                             search (Algorithm 3.1) at this step in tile-map voxels, then bisection [0] */
    int fixed_step;       /* with step: 1 keeps the step at grazing angles (the thesis's missed cells);
                             0 scales the first hit's step by max(|cos|, 1/8) of the angle to the base
                             mesh's normal (§3.2.2) [0] */
    int bisection_steps;  /* with step: refinement steps once a cell is bracketed [down to 1/64 voxel:
                             ceil(log2(64 step)), at least 1] */
    float reflectivity;   /* k of the reflection rule, 0..1 [0.5] */
    float ior;            /* refractive index of the cells [1.5] */
    float transparency;   /* tau of the refraction rule, 0..1 [0.7] */
    int max_steps;        /* voxel and tile steps per search; a search out of steps misses [4096] */
    uint32_t environment; /* GL name of a GL_TEXTURE_CUBE_MAP the host owns (linear RGB), looked up
                             (level 0) with the world-space direction of rays that leave the object;
                             0: the built-in sky of runtime/reference/cell_reference.h [0] */
    int footprint_rays;   /* far pixels, first hit, forward pass, MESO_FILTER_MIPMAP: 0 or 1 one ray a pixel;
                             N = 2..4: a pixel across more than two voxels shades the mean of N x N rays
                             across it (2 x 2 up to four voxels), which takes the far aliasing down (3:
                             0.28 of one ray's error on test_rt_mips's torus) at a cost (3: 3.5x that object's frame time;
                             bench_lod_scene's 1 px frame took 147 ms against 89, where the levels chosen
                             still put several voxels in a pixel) [0] */
} meso_rt_cells_draw;

/* Depth conventions (meso_rt_draw_desc.depth, .clip_depth): where the near
 * and far planes land in normalised device coordinates. The ray casters
 * unproject the near plane and a point between the planes, so an infinite
 * far plane works under each. */
typedef enum meso_depth_convention {
    MESO_DEPTH_STANDARD = 0, /* near plane at NDC z = -1 (0 with MESO_CLIP_DEPTH_ZERO_TO_ONE), far at +1;
                                the nearer fragment has the smaller depth (GL_LESS, GL_LEQUAL) */
    MESO_DEPTH_REVERSED      /* near at +1, far at 0 (or -1); the nearer fragment has the larger depth
                                (GL_GREATER, GL_GEQUAL): reversed-Z */
} meso_depth_convention;

typedef enum meso_clip_depth {
    MESO_CLIP_DEPTH_NEGATIVE_ONE_TO_ONE = 0, /* OpenGL's default */
    MESO_CLIP_DEPTH_ZERO_TO_ONE              /* after glClipControl(..., GL_ZERO_TO_ONE) (OpenGL 4.5 or
                                                ARB_clip_control; ES: EXT_clip_control) */
} meso_clip_depth;

/* What a draw writes (meso_rt_draw_desc.pass). Every pass writes the same
 * fragments with the same exact depth (tests/gl/test_rt_passes.c checks
 * the depth buffers are equal bit for bit); each kind compiles one program
 * variant per pass (lazily, or in meso_rt_prepare with
 * MESO_PREPARE_ALL_PASSES).
 *
 * Built-in shading, which the G-buffer lets a deferred renderer redo:
 * colour = albedo.rgb · albedo.a · (0.15 + 0.85 · max(0, n · l)), n the
 * G-buffer normal, l the unit world-space light_dir; meshes are two-sided:
 * |n · l| in place of max(0, n · l). */
typedef enum meso_rt_pass {
    MESO_PASS_FORWARD = 0, /* shaded colour into draw buffer 0 (the built-in Lambert or the shading hook) */
    MESO_PASS_DEPTH,       /* depth only (shadow maps, depth pre-passes): colour writes are masked for the
                              draw (glColorMask; put back under MESO_STATE_RESTORE, left masked under
                              MESO_STATE_HOST_OWNS) and the fragment shaders compute no normal and no
                              shading; cells trace only the first hit */
    MESO_PASS_GBUFFER,     /* into the host's attachments, which it binds with glDrawBuffers before the
                              draw: location 0 albedo: rgb the linear material colour (desc->albedo; for
                              cells the colour map's texel at the hit; for shells with a colour, COLR +
                              CMAP, FORMAT.md 7.2, the colour at the hit's texture point; for a mesh or
                              mesh stand-in with vertex colours, VCOL, FORMAT.md 7.3, theirs), a the
                              built-in occlusion factor
                              (shells and relief frusta 0.25 + 0.75 w, w the hit's height in the shell or
                              relief layer; a mesh's VCOL occlusion; 1 for other meshes, balls, smooth
                              frusta and cells); location 1 the
                              world-space unit shading normal, facing the viewer, encoded rgb = n · 0.5 +
                              0.5 (a = 1) for UNORM and float attachments alike; and the exact depth.
                              Cells in REFLECT / REFRACT modes write their first hit's material and normal
                              (the reflected and refracted light is view-dependent: forward only).
                              MESO_SHELL_SEGMENT_ONLY writes desc->albedo (a = 1) and the normal of the
                              hull face its depth lies on */
    MESO_PASS_COUNT
} meso_rt_pass;

/* One draw. Zero-initialise it (`meso_rt_draw_desc d = {0};`) and set what
 * differs from the defaults; designated initialisers read as
 * `{.view = ..., .proj = ..., .shell = {.technique = MESO_SHELL_CURVED}}`. */
typedef struct meso_rt_draw_desc {
    float view[16];            /* world -> eye, column-major (OpenGL convention) */
    float proj[16];            /* eye -> clip */
    float model[16];           /* object -> world: rotation, uniform scale, translation, mirroring
                                  allowed; other matrices (non-uniform scale, shear, projective) are
                                  refused with MESO_ERR_INVALID_ARG and a logged reason [all zero:
                                  identity] */
    float light_dir[3];        /* towards the light, world space [all zero: (0.3, 0.8, 0.5) normalised] */
    float albedo[3];           /* linear RGB [all zero: (0.80, 0.74, 0.66)]. Every kind writes linear
                                  colour: into an sRGB framebuffer (GL_SRGB8_ALPHA8 with
                                  GL_FRAMEBUFFER_SRGB enabled; on ES, any sRGB attachment) GL
                                  encodes it */
    meso_rt_draw_stats* stats; /* optional: filled after the draw (stalls the pipeline) [NULL] */
    meso_depth_convention depth; /* how proj maps depth [MESO_DEPTH_STANDARD] */
    meso_clip_depth clip_depth;  /* the context's clip control depth mode [NEGATIVE_ONE_TO_ONE] */
    uint32_t depth_func;         /* a GL depth function (GL_LESS, GL_GEQUAL, ...) to set for the draw;
                                    0: the host's, left as it is [0] */
    int32_t viewport[4];         /* the host's viewport (x, y, width, height), which the ray casters
                                    need; all zero: queried from GL (a glGet per draw) [0] */
    float pixel_error;           /* levelled objects (meso_rt_load_object_levels): the largest error on
                                    screen, in pixels of the viewport's height, a level may have; < 0:
                                    the finest level always [0: 1 pixel] */
    meso_rt_pass pass;           /* what the draw writes; MESO_SHELL_SLICES supports DEPTH and GBUFFER with
                                    MESO_SLICE_NONE only (the two-pass variants are refused with
                                    MESO_ERR_UNSUPPORTED, logged) [MESO_PASS_FORWARD] */
    meso_rt_shell_draw shell;   /* read for shells only */
    meso_rt_frusta_draw frusta; /* read for frusta only */
    meso_rt_cells_draw cells;   /* read for cells only */
} meso_rt_draw_desc;

/* Draw an object into the host's currently bound framebuffer and viewport,
 * with depth testing and depth writes under the host's depth function (or
 * desc->depth_func), so it sorts against the host's own geometry under
 * either depth convention. desc->pass chooses what is written besides the
 * depth: shaded colour, nothing, or the G-buffer (meso_rt_pass). Shells and frusta write the exact depth of the
 * ray's hit, and render correctly with the camera inside the shell or a
 * frustum (they rasterise back faces of their bounding geometry and see the
 * inner wall). Cells write the exact depth of the first hit; their rays
 * start on the base mesh's front faces, and when the camera is inside the
 * tile grid also at the near plane behind its back faces, so the camera may
 * be inside the object. Shells drawn with MESO_SHELL_SLICES write the depth
 * of their slice hit (MESO_SLICE_NONE: the first slice inside, up to one
 * slice spacing behind the surface along the ray; the two-pass variants:
 * the α = ½ crossing interpolated between two slices on the pixel's ray)
 * and draw their two-pass variants through an offscreen target the context
 * owns, sized to the viewport (runtime/rt_slices.c); their last pass, into
 * the host's framebuffer, uses desc->depth_func, else under
 * MESO_STATE_RESTORE the host's function, else GL_LESS (GL_GREATER
 * reversed); they fill no stats (supported = 0). Meshes are rasterised with
 * the host's face culling as it is. Shells, frusta and cells need the
 * inverse of proj · view · model (meshes too in MESO_PASS_GBUFFER and with a
 * shading hook): a singular one is refused with MESO_ERR_INVALID_ARG
 * (logged).
 *
 * GL state. A draw changes: the program, vertex array, active texture,
 * textures on units 0-4 (0-7 for slices), depth test (enabled) and mask
 * (written), the colour mask in MESO_PASS_DEPTH (all masked), the depth
 * function only with desc->depth_func, culling (shells and frusta:
 * enabled, front faces culled; cells: back faces culled, or culling off
 * when the camera is inside the tile grid; slices: off; the front face
 * counter-clockwise, clockwise under a mirroring model; meshes: the host's
 * culling, with the front face turned over under a mirroring model), where
 * stats are counted (OpenGL 4.3, ES 3.2 with fragment shader storage) the
 * generic shader storage buffer binding and indexed binding 0; for shells
 * with hull rejection (meso_rt_shell_draw.no_hull_reject) image unit 0 and,
 * when the prisms are re-sorted, the generic texture buffer binding; for
 * two-pass
 * slices also the draw framebuffer binding, the viewport, blending and the
 * depth function. Under MESO_STATE_RESTORE all of it is queried first and
 * put back before the call returns; under MESO_STATE_HOST_OWNS none of it
 * is queried or put back (and, with desc->viewport given, the draw makes
 * no glGet call at all, except: two-pass slices read the draw framebuffer
 * binding they composite into, and an instanced draw of an animated shell
 * uploads its frames as meso_rt_shell_set_time does). A mirroring mesh
 * under MESO_STATE_HOST_OWNS takes the host's front face to be GL's
 * counter-clockwise default. A depth-only draw under MESO_STATE_HOST_OWNS
 * leaves colour writes masked: the host turns them back on. The uniform
 * locations of every program are looked up once, when it links. The GL
 * error queue is read only with meso_rt_desc.check_gl_errors (then errors
 * are logged as GL_ERROR and returned as MESO_ERR_GL, never fatal). */
MESO_API meso_result meso_rt_draw(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* desc);

/* >>many objects ----------------------------------------------------------- */

/* One instance of an instanced draw. Zero-initialise it and set what
 * differs from the defaults. */
typedef struct meso_rt_instance {
    float model[16];    /* object -> world, the rules of meso_rt_draw_desc.model (similarity, else refused
                           naming the instance's index) [all zero: identity] */
    uint32_t pose_slot; /* frusta: the pose slot drawn (meso_rt_frusta_pose_slots) [0: the current pose] */
    int has_time;       /* shells with stored frames: 1 = draw the frame of `time` [0: the frame shown] */
    double time;        /* seconds, as meso_rt_shell_set_time (meso_anim_frame_at) */
} meso_rt_instance;

/* Draw `count` instances of one object in one instanced GL draw call
 * (glDrawArraysInstanced / glDrawElementsInstanced; animated shells: one
 * per frame the instances show, see below), each with its own
 * model matrix (desc->model is ignored) and, for frusta, its own pose slot.
 * An instance draws what meso_rt_draw would with desc->model = its model
 * (the same per-object values, computed on the CPU in double precision
 * and read by the same shaders from a texture buffer; tests/gl/
 * test_rt_instances.c compares the images with separate draws, bit for
 * bit, but where two prisms of a smooth or curved shell hit at exactly the
 * same depth: the instances share one prism order, sorted for the first
 * (meso_rt_shell_draw.no_hull_reject), and the order picks which colour
 * shows). Everything else, including the GL state changed and restored, is
 * meso_rt_draw's, plus the texture buffer binding (the instance data's
 * upload) and one more texture unit (5 for shells and cells, 2 for frusta,
 * 0 for meshes). Cells: when the near plane reaches into any instance's
 * grid, every instance's rays may start there too (the same image up to
 * rounding). Refused (MESO_ERR_INVALID_ARG, logged, nothing drawn): a
 * stale handle, NULL desc or instances, count 0, an instance whose model
 * is not a similarity (or makes the view singular), mirrored and
 * unmirrored instances in one call (the winding is one GL state: draw them
 * in two calls), a pose slot the object does not have, more instances than
 * the context's texture buffer holds (GL_MAX_TEXTURE_BUFFER_SIZE / 14).
 * MESO_SHELL_SLICES is not instanced (its two-pass variants composite
 * through one offscreen target per draw): MESO_ERR_UNSUPPORTED. Shells with
 * stored frames: each instance shows the frame of its time (has_time) or
 * the texture shown; the instances are drawn grouped by frame, the texture
 * shown first, with one instanced call and one frame upload (as
 * meso_rt_shell_set_time) per further frame, so afterwards the shell shows
 * the last group's frame; a NaN time is refused naming the instance.
 * Objects with levels (meso_rt_load_object_levels): each instance draws
 * the level it would draw alone (its own distance against pixel_error),
 * one instanced call per level, finest first; the image is that of
 * separate meso_rt_draw calls. Instances that are not similarities or mix
 * mirroring are refused as one call; a refusal of one instance's frame,
 * pose slot or texture-buffer room refuses its level's call, and the
 * levels before it stay drawn. meso_rt_draw_list's instanced items take
 * one level for all their instances (the nearest's). */
MESO_API meso_result meso_rt_draw_instanced(meso_rt* rt, meso_rt_object obj, const meso_rt_draw_desc* desc,
                                            const meso_rt_instance* instances, uint32_t count);

/* One item of meso_rt_draw_list. */
typedef struct meso_rt_draw_item {
    meso_rt_object object;
    float model[16];                     /* object -> world, as meso_rt_draw_desc.model; ignored with
                                            instances [all zero: identity] */
    const meso_rt_draw_desc* knobs;      /* optional: this item's albedo, shell / frusta / cells knobs and
                                            stats instead of common's [NULL] */
    const meso_rt_instance* instances;   /* optional: draw the item instanced [NULL] */
    uint32_t instance_count;             /* with instances: how many (> 0) [0] */
} meso_rt_draw_item;

/* Draw a list of objects in one call: each item as meso_rt_draw (or
 * meso_rt_draw_instanced) would with `common` (view, proj, light, depth
 * conventions, viewport, and the knobs of items without their own), sorted
 * by kind, program (shell technique, stats) and object so that each
 * program is bound once; the items of one key keep the caller's order.
 * Under MESO_STATE_RESTORE the state is saved once before the first item
 * and restored once after the last (texture units 0-7 of every target the
 * kinds bind, besides meso_rt_draw's list); the items' own draws query and
 * restore nothing (slices items excepted: their offscreen passes save and
 * restore as in meso_rt_draw). An item that fails is logged and skipped,
 * the others are drawn, and the first failure is returned. Refused before
 * anything is drawn (MESO_ERR_INVALID_ARG): NULL items or common, count 0,
 * an item with a stale handle or instance_count without instances. Work
 * counters (`stats`) are filled per draw: items sharing common's stats
 * leave in it the counts of the last of them drawn (in sorted order); give
 * an item its own knobs for its own counts. */
MESO_API meso_result meso_rt_draw_list(meso_rt* rt, const meso_rt_draw_item* items, uint32_t count,
                                       const meso_rt_draw_desc* common);

/* Animation without re-baking: replace a shell's base positions (3 floats
 * per vertex) and directors (3 floats per vertex per SDIR layer, the layout
 * of its SDIR chunk); either may be NULL to keep it. vertex_count must equal
 * the shell's, in the order of its MESH chunk: a textured bake splits
 * vertices at uv seams (mesobake's report: texture.seam_vertices), the
 * copies first appearing after the mesh's own vertices and sharing their
 * positions, so give every copy its source vertex's values. Cost: one buffer
 * upload of 24 bytes per vertex. */
MESO_API meso_result meso_rt_shell_update(meso_rt* rt, meso_rt_object obj, const float* positions,
                                          const float* directors, uint32_t vertex_count);
/* Vertex count and SDIR layer count of a shell (0 for other kinds). */
MESO_API meso_result meso_rt_shell_info(const meso_rt* rt, meso_rt_object obj, uint32_t* vertex_count,
                                        uint32_t* layers);

/* >>animated texture functions -------------------------------------------- */

/* Texture functions that change over time (papers/volume-textures-lp-
 * averaged-shells.md §6, the boiling textures): replace a shell's function
 * and distance map between frames without reloading it, or select one of
 * the frames stored in its file (FORMAT.md §7.2 "Animated texture
 * functions"; mesobake shell --texture boil --frames N). */
typedef enum meso_rt_texture_kind {
    MESO_RT_TEXTURE_HEIGHT = 1,  /* height field h(s, t'), dims W x H x 1 (a TX2D) */
    MESO_RT_TEXTURE_DENSITY = 2  /* density alpha(s, t', w), dims W x H x D (a TX3D) */
} meso_rt_texture_kind;

/* A texture function in host memory, laid out and interpreted as its
 * FORMAT.md §7.2 chunk: values s fastest, then t', then w, value / max. */
typedef struct meso_rt_shell_texture {
    meso_rt_texture_kind kind;
    uint32_t dims[3];      /* each 1..the context's (3D) texture size limit; dims[2] = 1 for a height field */
    uint16_t dtype;        /* MESO_DTYPE_U8 or MESO_DTYPE_U16 */
    const void* data;      /* dims[0] * dims[1] * dims[2] values */
    uint32_t dist_dims[3]; /* the distance map's cells; all 0: none (rays march at fixed_step) */
    uint16_t dist_dtype;   /* MESO_DTYPE_U8, _U16 (value / max) or _F32 (finite, >= 0) */
    const void* dist_data; /* dist_dims[0] * dist_dims[1] * dist_dims[2] values, or NULL with no map */
} meso_rt_shell_texture;

/* Replace the texture function and distance map of a SHELL object. Any
 * dims and kind are accepted (they need not match the file's): the call
 * uploads new textures and, once both are complete, deletes the old ones,
 * so the size may change from call to call; the distance map must bound the
 * new function (FORMAT.md §7.2) or rays may step over the surface. The
 * data is copied; the host keeps its buffers. Fails with
 * MESO_ERR_INVALID_ARG (logged, nothing changed) for a handle that is not a
 * live shell, a NULL desc or data, an unknown kind or dtype, a zero
 * dimension or one above GL_MAX_TEXTURE_SIZE / GL_MAX_3D_TEXTURE_SIZE, a
 * height field with dims[2] != 1, dist_data without dist_dims (or the
 * reverse), or an F32 distance that is not finite and >= 0; with
 * MESO_ERR_GL when GL raises an error (out of memory): then the new
 * textures are deleted and the object still draws its previous function.
 * The GL state it touches (texture buffer binding, the active unit's 2D/3D
 * texture binding, unpack alignment) is restored. Cost: one texture upload
 * of each; tests/bench/bench_anim_update.c measures it. */
MESO_API meso_result meso_rt_shell_set_texture(meso_rt* rt, meso_rt_object obj, const meso_rt_shell_texture* desc);

/* Show the stored frame for time `seconds` (meso_anim_frame_at: frame k
 * from time0 + k / fps on, looped), uploading it as meso_rt_shell_set_texture
 * does when it is not the frame shown already. A shell without stored
 * frames is left alone (MESO_OK). After meso_rt_shell_set_texture the next
 * call always uploads. MESO_ERR_INVALID_ARG for a handle that is not a live
 * shell or a NaN time; MESO_ERR_GL as meso_rt_shell_set_texture. */
MESO_API meso_result meso_rt_shell_set_time(meso_rt* rt, meso_rt_object obj, double seconds);

/* Stored frames of a shell: count (0: none, or not a shell), rate, and
 * the frame shown (UINT32_MAX: none, or a host texture from
 * meso_rt_shell_set_texture). Any output may be NULL. */
MESO_API meso_result meso_rt_shell_anim_info(const meso_rt* rt, meso_rt_object obj, uint32_t* frame_count, float* fps,
                                             uint32_t* frame);

/* >>frusta animation ------------------------------------------------------ */

/* Animation without re-baking (papers/relief-mapped-conical-frusta.md §4:
 * "the splitting planes between segments have to be recomputed in each time
 * step"): move the skeleton's nodes and rebuild every frustum of a FRUSTA
 * object from them — cutting planes, end centres and radii, u frames and
 * offsets (FORMAT.md §7.2 "Animation", formats/frusta_pose.h), ball centres
 * — then its bounding pyramids, and upload. `node_positions` holds 3 floats
 * per SKEL node, in SKEL order, in object space; node_count must equal the
 * object's (meso_rt_frusta_info). Radii and relief parametrisation stay as
 * baked. Fails with MESO_ERR_INVALID_ARG (logged, nothing changed) for a
 * handle that is not a live frusta object, a wrong count, or a pose that
 * collapses a frustum to zero length. The object's bounds
 * (meso_rt_object_bounds) become those of the new bounding geometry. Cost
 * per 1000 frusta: tests/bench/bench_frusta.c (bench_frusta.csv). */
MESO_API meso_result meso_rt_frusta_set_pose(meso_rt* rt, meso_rt_object obj, const float* node_positions,
                                             uint32_t node_count);
/* Pose slots for instanced draws (meso_rt_instance.pose_slot): the object
 * keeps `slots` poses side by side on the GPU (slot 0 is the current pose,
 * the one meso_rt_frusta_set_pose moves and meso_rt_draw draws), each with
 * its own bounding geometry (meso_rt_object_bounds stays slot 0's). New
 * slots start as a copy of slot 0; shrinking
 * drops the last ones. 1..the texture buffer's limit (GL_MAX_TEXTURE_BUFFER_
 * SIZE / 16 texels per primitive). Cost: a re-upload of every slot (256
 * bytes per primitive per slot). MESO_ERR_INVALID_ARG (logged, nothing
 * changed) for a handle that is not a live frusta object or a bad count,
 * MESO_ERR_GL when GL cannot store them (the old slots stay). */
MESO_API meso_result meso_rt_frusta_pose_slots(meso_rt* rt, meso_rt_object obj, uint32_t slots);
/* meso_rt_frusta_set_pose for one pose slot: the slot's frusta are rebuilt
 * from its own previous pose (as a separate object posed with the same
 * sequence of meso_rt_frusta_set_pose calls would be), and only its part
 * of the buffer is uploaded. Slot 0 is meso_rt_frusta_set_pose itself.
 * MESO_ERR_INVALID_ARG (logged, nothing changed) as meso_rt_frusta_set_pose,
 * and for a slot the object does not have. */
MESO_API meso_result meso_rt_frusta_set_pose_slot(meso_rt* rt, meso_rt_object obj, uint32_t slot,
                                                  const float* node_positions, uint32_t node_count);
/* Frustum and skeleton node counts of a FRUSTA object (0 for other kinds).
 * Either output may be NULL. */
MESO_API meso_result meso_rt_frusta_info(const meso_rt* rt, meso_rt_object obj, uint32_t* frustum_count,
                                         uint32_t* node_count);
/* The rest pose: the SKEL node positions the file was baked with (3 floats
 * per node) into `positions`, and optionally (`parents` not NULL) each
 * node's parent index (−1 for a root; parents come before their children).
 * Both hold node_count entries, which must equal the object's count. Hosts
 * animate by moving these and calling meso_rt_frusta_set_pose. */
MESO_API meso_result meso_rt_frusta_rest_pose(const meso_rt* rt, meso_rt_object obj, float* positions,
                                              int32_t* parents, uint32_t node_count);

#ifdef __cplusplus
}
#endif
#endif /* MESO_RT_H */
