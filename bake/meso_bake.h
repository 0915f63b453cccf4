/*
 * meso_bake.h — libmeso_bake, the baker's public C API: the whole pipeline
 * of `mesobake`, in-process.
 *
 *   load      meso_bake_load_mesh      a mesh by extension (.obj .off .ply .stl
 *                                      .om through OpenMesh, .drc through Draco),
 *                                      after the mesh guard, checked and turned
 *                                      outward
 *             meso_bake_skeleton_load  a skeleton (.swc, text, or from a mesh)
 *             meso_bake_texture_probe  a texture function / relief SPEC
 *   bake      meso_bake_mesh  meso_bake_shell  meso_bake_cells  meso_bake_frusta
 *             each takes an options struct (start from meso_bake_*_defaults(),
 *             which are the CLI's defaults) and fills a report struct with the
 *             numbers of the JSON report; the result is a meso_bake_output
 *   write     meso_bake_output_write_file  (atomic, to a path)
 *             meso_bake_output_write       (into a staged meso_output the
 *                                           caller opened and will commit)
 *             meso_bake_output_copy        (the bytes, into a caller buffer)
 *
 * A bake is deterministic: the same inputs and options give the same bytes,
 * whatever the thread count; `mesobake` is a thin program over this API, so
 * the bytes are the CLI's.
 *
 * Memory: a bake's result is a meso_bake_output holding the encoded chunks
 * once (the stages' working buffers are freed before the bake returns). The
 * write functions stream those chunks to a file descriptor one by one, so
 * writing never needs a second, whole-file buffer; meso_bake_output_copy is
 * for small bakes and callers that want bytes in memory. A staged output
 * (meso_output, meso_file.h) lets a program publish several files together
 * and remove a temporary file on a signal, which this library never handles.
 *
 * Errors: every function that can fail returns a meso_result and fills the
 * meso_error (may be NULL): `code` is an issue number (list below), `message`
 * names the problem and where (file, line, face, option). Warnings (e.g.
 * E3250, inside-out components turned outward) go to the progress callback
 * and into the report. The library never prints, never exits, never installs
 * a signal handler.
 *
 * Linking: pkg-config meso-bake. The shared library exports the functions
 * marked MESO_BAKE_API and nothing else. meso_file.h (installed beside this
 * header by libmeso) gives the result, error and output types; link libmeso
 * too to use its functions (meso_result_string, meso_output_open, ...).
 *
 * Also declared here: meso_mesh, the bake's in-memory mesh, with helpers
 * the stages share (they are public so meso_bake_load_mesh can return one).
 */
#ifndef MESO_BAKE_H
#define MESO_BAKE_H

#include <stddef.h>
#include <stdint.h>

#include "meso_file.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Marks the exported functions. Building libmeso_bake (MESO_BAKE_BUILD,
 * with -fvisibility=hidden), they get default visibility; elsewhere the
 * macro is empty. Define it before including this header to override. */
#ifndef MESO_BAKE_API
#if defined(MESO_BAKE_BUILD) && (defined(__GNUC__) || defined(__clang__))
#define MESO_BAKE_API __attribute__((visibility("default")))
#else
#define MESO_BAKE_API
#endif
#endif

/* >>mesh ------------------------------------------------------------------ */

/* An indexed triangle mesh in host memory (the bake's working form).
 * Arrays are malloc'd and owned by the struct: free with meso_mesh_free. */
typedef struct meso_mesh {
    uint32_t vertex_count;
    uint32_t triangle_count;
    float* positions; /* 3 * vertex_count */
    float* normals;   /* 3 * vertex_count, or NULL */
    float* uvs;       /* 2 * vertex_count, or NULL */
    uint32_t* indices; /* 3 * triangle_count, counter-clockwise seen from outside */
    /* 6 * triangle_count (uv of each face corner, in `indices` order), or NULL.
     * The OpenMesh reader sets it when the input has per-corner texture
     * coordinates (OBJ `f v/vt`) and some vertex has more than one (a texture
     * seam); `uvs` is then set too (one uv per vertex, as without it). NULL
     * means `uvs` says it all. Last, so positional initialisers stay valid. */
    float* corner_uvs;
} meso_mesh;

/* A material's base colour (glTF pbrMetallicRoughness). */
typedef struct meso_mesh_material {
    float base_color_factor[4]; /* linear RGBA, default 1 */
    uint32_t width, height;     /* base-colour texture size; 0 when none */
    uint8_t* rgba;              /* width * height RGBA8 texels as stored (sRGB), first row first, or NULL */
    uint32_t texcoord;          /* the TEXCOORD_n set the texture names (only TEXCOORD_0 is read) */
} meso_mesh_material;

/* The materials of a loaded mesh (glTF input; empty for other formats):
 * triangle_materials[t] indexes `materials` for triangle t of the mesh as
 * loaded (UINT32_MAX: none). mesobake shell --color from-mesh reads it
 * (bake/shell_color.h). */
typedef struct meso_mesh_materials {
    uint32_t material_count;
    meso_mesh_material* materials;
    uint32_t* triangle_materials; /* triangle_count entries, or NULL */
} meso_mesh_materials;

/* Frees the arrays and zeroes the struct. NULL is allowed. */
MESO_BAKE_API void meso_mesh_materials_free(meso_mesh_materials* m);

/* Frees the arrays and zeroes the struct. NULL is allowed. */
MESO_BAKE_API void meso_mesh_free(meso_mesh* m);

/* Unit normal of face f (CCW seen from outside) into n; returns twice the
 * face's area (0, with n = 0, for a degenerate face). */
MESO_BAKE_API double meso_mesh_face_normal(const meso_mesh* m, uint32_t f, double n[3]);

/* Axis-aligned bounds of the positions; returns the diagonal length. */
MESO_BAKE_API double meso_mesh_bounds(const meso_mesh* m, double lo[3], double hi[3]);

/* >>issues ---------------------------------------------------------------- */

/* Issue codes of bake inputs (meso_error.code; mesobake prints "E<code>").
 * Format issues keep FORMAT.md's numbers (1xxx-5xxx); inputs use 31xx:
 *   3100 the mesh reader rejected the file     3110 non-manifold edges/vertices
 *   3101 non-finite coordinate                 3111 inconsistent orientation
 *   3102 face refers to a missing vertex       3112 duplicated faces
 *                                              3113 degenerate faces
 *                                              3114 the surface intersects itself
 *   3115 mesobake shell: the baked shell keeps inverted prisms or
 *        intersections (exit 8 unless --allow-defects)
 * Texture functions (mesobake shell --texture, bake/texture_function.h):
 *   3120 the texture SPEC does not parse       3122 texture file content unusable
 *   3121 texture file missing or unreadable    3123 .vdb: no such float grid, or empty
 *   (3124..3129 reserved for texture functions and distance maps)
 * Shell colour (mesobake shell --color, bake/shell_color.h):
 *   3130 the colour SPEC does not parse        3132 colour file content unusable
 *   3131 colour file missing or unreadable     3133 from-mesh: no single usable
 *                                                   base colour in the input
 * Skeletons (bake/skeleton_swc.h): 3140..3149, each listed there.
 * Cell tile maps and split cells (bake/tile_map.h, bake/split_cells.h):
 *   3150..3153, listed in tile_map.h.
 * Winding numbers (bake/winding_number.h): 3160..3169, listed there.
 * Skeletons from meshes (bake/skeleton_from_mesh.h): 3170..3179, listed there.
 * Voxelization and membership maps (bake/voxelize.h, bake/membership.h):
 *   3180..3189, listed there.
 * Cells-object chunks (bake/cells_chunks.h): 3190..3194, listed there.
 * Mesh files before any reader sees them (bake/mesh_guard.h): 3200..3249,
 *   listed there.
 * Input meshes, whole-file and orientation: 3250..3299 —
 *   3250 (a warning) inside-out closed components were flipped (mesh_orient.h)
 *   3251 not a mesh file mesobake can read (unknown extension, e.g. /dev/null)
 *   3252 no triangles (an empty file, or not a mesh)
 * Skeletons, continued (bake/skeleton_swc.h): 3300..3349, listed there.
 * glTF 2.0 input (bake/gltf_model.h): 3500..3519, listed there.
 * Limits up front, --max-memory (bake/memory_budget.h): 3400..3449, listed
 *   there (3400 a request from the options, 3401.. sizes input files dictate).
 * Batch manifests (mesobake batch, tools/mesobake/batch.h): 3450..3469,
 *   listed there.
 * Packing .meso files (meso_bake_pack, below): 3480..3489.
 * (The bake/ headers named are the library's sources, not installed.) */
#define MESO_BAKE_ISSUE_UNREADABLE 3100u
#define MESO_BAKE_ISSUE_SHELL_DEFECTS 3115u
#define MESO_BAKE_ISSUE_REORIENTED 3250u /* a warning */

/* Fill an error struct (printf-style message; err may be NULL). Returns `r`.
 * The library's own helper, exported for hosts that report their own
 * failures the same way. */
MESO_BAKE_API meso_result meso_bake_fail(meso_error* err, meso_result r, uint32_t code, const char* fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* >>progress -------------------------------------------------------------- */

typedef enum meso_bake_event {
    MESO_BAKE_EVENT_STAGE = 0, /* a stage finished; `message` is its one-line summary (or NULL) */
    MESO_BAKE_EVENT_TICK,      /* progress inside a long stage: `done` of `total` items */
    MESO_BAKE_EVENT_WARNING,   /* `message` is a warning, `code` its issue number (0: none) */
    MESO_BAKE_EVENT_COUNT
} meso_bake_event;

typedef struct meso_bake_progress {
    meso_bake_event event;
    const char* stage;   /* short name: "load", "texture", "distance map", "directors", ... */
    double fraction;     /* of the whole bake, in [0, 1]; never decreases; the last call has 1 */
    const char* message; /* STAGE: the line `mesobake -v` prints after "mesobake: "; WARNING:
                            the text after "mesobake warning: "; NULL for TICK. Valid
                            during the call only */
    uint32_t code;       /* WARNING: issue number, e.g. 3250; else 0 */
    uint64_t done, total; /* TICK: items done of the stage's total (may arrive out of order) */
} meso_bake_progress;

/* Called on the calling thread, except TICK events, which may come from a
 * worker thread (one call at a time). Must not call back into a bake. */
typedef void (*meso_bake_progress_fn)(void* user, const meso_bake_progress* p);

/* What every bake and loader takes. Zero means: no callback, default budget,
 * all cores. */
typedef struct meso_bake_common {
    uint64_t max_memory;            /* bytes a bake may plan to allocate; refused up front
                                       (code 3400..) when its estimate is larger. 0 = half of
                                       physical memory (mesobake --max-memory) */
    int threads;                    /* worker threads, 0 = all cores; never changes the bytes */
    meso_bake_progress_fn progress; /* stage lines, ticks and warnings; may be NULL */
    void* user;                     /* passed to `progress` */
    const char* gltf_node;          /* glTF input: bake only this node's subtree (its name, else a
                                       decimal index; mesobake --node); NULL: the whole scene */
} meso_bake_common;

/* >>load ------------------------------------------------------------------ */

/* What meso_bake_load_mesh changed in (or could not check about) a mesh;
 * every bake report starts with it. */
typedef struct meso_bake_mesh_fixes {
    uint32_t reoriented_components; /* inside-out closed components flipped (warning E3250) */
    uint32_t closed_components;     /* closed components looked at */
    uint32_t reoriented_faces;      /* faces flipped */
    int orientation_unchecked;      /* 1: too many nested components to check; left as they are */
} meso_bake_mesh_fixes;

/* Load a mesh by extension: its bytes through the mesh guard (with
 * c->max_memory as the bound on what its header counts may make a reader
 * allocate), then OpenMesh (.obj .off .ply .stl .om) or Draco (.drc), or a
 * glTF 2.0 scene (.gltf .glb: every triangle primitive in world space, or
 * c->gltf_node's subtree, positions welded, bake/gltf_model.h); then
 * check it (finite coordinates, indices in range, nothing the reader had to
 * drop) and turn inside-out closed components outward (a WARNING through
 * c->progress). `c` and `fixes` may be NULL. On success the caller frees *m
 * with meso_mesh_free; on failure *m is zeroed and err->code is set (3100
 * for a file the readers reject, 5001/5004 for I/O). A build without the
 * needed adapter returns MESO_ERR_UNSUPPORTED. */
MESO_BAKE_API meso_result meso_bake_load_mesh(const char* path, const meso_bake_common* c, meso_mesh* m,
                                              meso_bake_mesh_fixes* fixes, meso_error* err);
/* The same, with the materials' base colour of a glTF input into
 * *materials (zeroed for other formats; free with meso_mesh_materials_free;
 * on failure it is zeroed). */
MESO_BAKE_API meso_result meso_bake_load_mesh_materials(const char* path, const meso_bake_common* c, meso_mesh* m,
                                                        meso_mesh_materials* materials,
                                                        meso_bake_mesh_fixes* fixes, meso_error* err);

/* A loaded skeleton (opaque). */
typedef struct meso_bake_skeleton meso_bake_skeleton;

typedef struct meso_bake_skeleton_info {
    const char* input;       /* "swc", "text" or "mesh" (static string) */
    uint32_t node_count;
    uint32_t root_count;
    /* Mesh input only (skeleton by mean-curvature flow, CGAL), else 0: */
    double tolerance;        /* the simplification tolerance used */
    double bbox_diagonal;    /* of the mesh */
    double fit_error_max;    /* two-sided distance frusta <-> mesh */
    double fit_error_mean;   /* mean distance of the mesh's vertices to the frusta */
    double mesh_to_frusta_max;
    double frusta_to_mesh_max;
    uint32_t mesh_triangles;
    uint32_t skeleton_nodes_extracted; /* CGAL's nodes before simplification */
    meso_bake_mesh_fixes fixes;        /* mesh input: what loading the mesh changed */
} meso_bake_skeleton_info;

/* Load a skeleton: .swc (SWC), a mesh extension (.obj .off .ply .stl .om
 * .drc: skeleton extracted by CGAL, simplified to `tolerance` mesh units,
 * 0 = 1 % of the bounding-box diagonal), anything else the text format
 * "x y z radius [parent]" per line. A skeleton file is checked against
 * c->max_memory before it is read. `c` and `info` may be NULL. Free *out
 * with meso_bake_skeleton_free. */
MESO_BAKE_API meso_result meso_bake_skeleton_load(const char* path, double tolerance, const meso_bake_common* c,
                                                  meso_bake_skeleton** out, meso_bake_skeleton_info* info,
                                                  meso_error* err);
MESO_BAKE_API void meso_bake_skeleton_free(meso_bake_skeleton* s);

/* A texture function or relief SPEC, as `mesobake shell --texture` and
 * `mesobake frusta --relief` take it:
 *   height:FILE.png  volume:FILE.raw:WxHxD  volume:FILE.vdb[:GRID]
 *   bricks[:RES]  cobble[:RES]  ribs[:RES]     (built-in height fields)
 *   weave[:RES]  cells[:RES]  icospheres[:RES] (built-in density volumes) */
typedef struct meso_bake_texture_info {
    int density;       /* 0: a height field (TX2D, RELF), 1: a density volume (TX3D) */
    uint32_t dims[3];  /* texels W, H, D (D = 1 for a height field) */
    uint16_t dtype;    /* MESO_DTYPE_U8 or MESO_DTYPE_U16 */
} meso_bake_texture_info;

/* Parse and sample `spec` (checked against c->max_memory), fill *info and
 * free the samples: an editor's check of a SPEC before a bake. Codes
 * 3120..3123, 3400, 3401. `c` may be NULL. */
MESO_BAKE_API meso_result meso_bake_texture_probe(const char* spec, const meso_bake_common* c,
                                                  meso_bake_texture_info* info, meso_error* err);

/* >>output ---------------------------------------------------------------- */

/* A baked .meso file, ready to write: META, RPRT (the report as JSON, no
 * timings), OBJT and the object's chunks, encoded. Opaque; free with
 * meso_bake_output_free. */
typedef struct meso_bake_output meso_bake_output;

/* Size of the file in bytes. */
MESO_BAKE_API size_t meso_bake_output_size(const meso_bake_output* o);
/* The JSON text of the RPRT chunk (compact, NUL-terminated, owned by `o`). */
MESO_BAKE_API const char* meso_bake_output_report_json(const meso_bake_output* o);
/* Write to `path` atomically (a temporary file beside it, fsync, rename; see
 * meso_writer_write_file in meso_file.h). */
MESO_BAKE_API meso_result meso_bake_output_write_file(meso_bake_output* o, const char* path, meso_error* err);
/* Write into a staged output the caller opened (meso_output_open, or a
 * program's own staging) and will commit or abort. */
MESO_BAKE_API meso_result meso_bake_output_write(meso_bake_output* o, meso_output* staged, meso_error* err);
/* Copy the file's bytes into dst; with dst == NULL only *needed is set.
 * MESO_ERR_INVALID_ARG when dst_size is too small. */
MESO_BAKE_API meso_result meso_bake_output_copy(meso_bake_output* o, void* dst, size_t dst_size, size_t* needed);
MESO_BAKE_API void meso_bake_output_free(meso_bake_output* o);

/* >>mesh bake --------------------------------------------------------------- */

/* The most quantisation bits meso asks of Draco for any attribute. Draco
 * (1.5.5, Debian 12) entropy-codes each quantised attribute with a table
 * over its whole range: on the 642-vertex sphere one 30-bit attribute took
 * 13 s and 4.2 GB, one of 24 bits 0.25 s and 100 MB (mesobake mesh
 * --draco-bits 30,10,12 and 14,24,12), doubling per bit. 24 bits is also all a float32 holds
 * (a 24-bit significand): a step of 2^-24 of the box is already at the
 * float spacing of its largest coordinates. */
#define MESO_DRACO_MAX_BITS 24

typedef struct meso_bake_mesh_options {
    meso_bake_common common;
    const char* input;       /* mesh path, or NULL with `mesh` */
    const meso_mesh* mesh;   /* or, with input NULL: a mesh in memory, copied and checked as a loaded
                                file is (elements, manifold, oriented edges; orientation fixed); META
                                names it "(memory)" with the crc32c of its positions and indices */
    const char* name;        /* object name; NULL = the input's base name, or "mesh" (31 bytes kept) */
    int draco;               /* 1: store the mesh Draco-compressed (quantised) */
    int draco_position_bits; /* 1..MESO_DRACO_MAX_BITS; 0 = 14 */
    int draco_normal_bits;   /* 2..MESO_DRACO_MAX_BITS; 0 = 10 */
    int draco_uv_bits;       /* 1..MESO_DRACO_MAX_BITS; 0 = 12 */
    int levels;              /* levels of detail, level 0 included (FORMAT.md §7.10): 0 = auto (halve the
                                triangles per level while a level keeps < 85 % of the previous one's and that
                                had > 256, at most 8 levels), 1 = the finest only (no LODS chunk, the file of
                                earlier versions), N = at most N (1..MESO_BAKE_MESH_MAX_LEVELS). Coarse levels
                                need meshoptimizer: without it auto gives one level, N > 1 fails UNSUPPORTED */
    int parts;               /* the mesh also cut into parts with levels of their own (FORMAT.md §7.11), so a
                                reader can draw the near end finer than the far end: 0 = auto (parts of about
                                1024 triangles, when there are levels and at least 2048 triangles), N > 0 = parts
                                of about N triangles (at least 64), -1 = none */
} meso_bake_mesh_options;

#define MESO_BAKE_MESH_MAX_LEVELS 16

/* One level of a mesh bake. */
typedef struct meso_bake_mesh_level {
    uint32_t vertices;
    uint32_t triangles;
    double error;         /* object units: measured upper bound of the distance to level 0's surface
                             (0 at level 0; non-decreasing) */
    double sample_radius; /* the sampling radius included in `error` (0 at level 0) */
    size_t mesh_bytes;    /* stored MESH payload */
} meso_bake_mesh_level;

typedef struct meso_bake_mesh_report {
    meso_bake_mesh_fixes fixes;
    uint32_t vertices;
    uint32_t triangles;
    double bbox_diagonal;
    int draco;         /* the encoding: 0 raw, 1 draco */
    size_t mesh_bytes; /* stored MESH payload */
    int has_normals;   /* the input had normals (or OpenMesh computed them) */
    int has_uvs;
    uint32_t level_count; /* levels written, level 0 included (1: no LODS chunk) */
    meso_bake_mesh_level level[MESO_BAKE_MESH_MAX_LEVELS];
    uint32_t parts;       /* parts written (0: none) */
    uint32_t part_levels; /* part levels written, level 0 of each included */
    size_t part_bytes;    /* stored PMSH and PRTS payload */
} meso_bake_mesh_report;

/* Zero: the CLI's defaults (raw encoding). */
MESO_BAKE_API meso_bake_mesh_options meso_bake_mesh_defaults(void);

/* `mesobake mesh`: the input as one MESH object. On success *out is the
 * file (free with meso_bake_output_free); `report` may be NULL. */
MESO_BAKE_API meso_result meso_bake_mesh(const meso_bake_mesh_options* o, meso_bake_output** out,
                                         meso_bake_mesh_report* report, meso_error* err);

/* >>shell bake -------------------------------------------------------------- */

typedef enum meso_shell_kind {
    MESO_SHELL_EXTERIOR = 0, /* directors leave the surface along +normal */
    MESO_SHELL_INTERIOR,     /* along -normal, into the solid */
    MESO_SHELL_ENVELOPE,     /* both: half the thickness on each side */
    MESO_SHELL_KIND_COUNT
} meso_shell_kind;

/* How shell directors are made (mesobake shell --directors). */
typedef enum meso_shell_directors {
    MESO_DIRECTORS_HYBRID = 0, /* normal displacement where provably safe, the Lp field elsewhere */
    MESO_DIRECTORS_LP,         /* the Lp-averaged distance field everywhere */
    MESO_DIRECTORS_NORMAL,     /* plain normal displacement (folds at concavities) */
    MESO_DIRECTORS_COUNT
} meso_shell_directors;

/* "exterior", "interior", "envelope" / "hybrid", "lp", "normal" (the CLI's
 * and META's words); NULL when out of range. */
MESO_BAKE_API const char* meso_bake_shell_kind_name(meso_shell_kind k);
MESO_BAKE_API const char* meso_bake_directors_name(meso_shell_directors d);

#define MESO_BAKE_MAX_P 16.0       /* --p: in (2, MESO_BAKE_MAX_P] */
#define MESO_BAKE_MAX_DIST_RES 512u /* --dist-res: each axis 1..this */
#define MESO_BAKE_MAX_FRAMES 256u   /* --frames: 1..this */

typedef struct meso_bake_shell_options {
    meso_bake_common common;
    const char* input;           /* mesh path, or NULL with `mesh` */
    const meso_mesh* mesh;   /* or, with input NULL: a mesh in memory, copied and checked as a loaded
                                file is (elements, manifold, oriented edges; orientation fixed); META
                                names it "(memory)" with the crc32c of its positions and indices */
    double thickness;            /* mesh units; 0 = thickness_rel of the bbox diagonal */
    double thickness_rel;        /* default 0.05 */
    meso_shell_kind kind;        /* default exterior */
    meso_shell_directors directors; /* default hybrid */
    double p;                    /* exponent of the averaged distance, (2, 16], default 3 */
    double theta;                /* Barnes-Hut opening angle, 0 = exact, default 0.5 */
    double angle_tol_deg;        /* largest turn of the field per Euler step, default 5 */
    int smooth;                  /* Laplacian smoothing rounds of traced directors, default 0 */
    int no_repair;               /* 1: keep directors that still fold (default 0: shorten them) */
    /* Texture function (what the shell holds); NULL: the whole shell is solid. */
    const char* texture;         /* SPEC, see meso_bake_texture_info */
    double tiling[2];            /* tiles along u, v; default 1, 1 */
    uint32_t dist_res[3];        /* distance-map cells; 0 = the default for the texture */
    uint16_t dist_dtype;         /* MESO_DTYPE_U8 (default), _U16 or _F32 */
    /* Animated texture functions (volume-textures-lp-averaged-shells.md §6),
     * only for a time-dependent built-in (boil; FORMAT.md §7.2 "Animated
     * texture functions"): */
    double time;                 /* seconds: the time the texture is sampled at (frame 0's) [0] */
    uint32_t frames;             /* 0: static; 1..256: that many frames, time + k / fps, stored as
                                    ANIM + TXFR + DSFR (frame 0 also as the TX3D + DIST) [0] */
    double fps;                  /* frames per second; 0: frames / the texture's period, so the
                                    sequence loops seamlessly [0] */
    /* Incremental re-bake (volume-textures-lp-averaged-shells.md §6,
     * "Deformations"; bake/shell_update.c): the .meso file of a previous
     * bake of this mesh before an edit that moved vertices but kept the
     * topology. Directors are recomputed only within the edit's influence
     * radius, the rest are the old file's; the parameters (kind, directors,
     * p, theta, angle_tol_deg, smooth, no_repair and, when `thickness` is
     * given, the thickness) must be the old bake's; without `thickness` the
     * old bake's thickness is kept (an edit may move the diagonal that
     * thickness_rel refers to). The report's vertices_lp / vertices_normal
     * then count the recomputed vertices only. OLD's simplified stand-in
     * levels (`levels`) are kept, each error raised by the farthest any
     * vertex moved, while their base mesh has moved no farther than the
     * base-mesh stand-in's error over this and earlier updates, `levels` is
     * OLD's and they fit beside this bake's native levels; otherwise
     * they are built anew (report: update_levels_kept). NULL: a full bake. */
    const char* update;
    /* Colour function (FORMAT.md §7.2 "Shell colour"; needs `texture`); NULL: none. SPEC:
     * FILE.png (2D, tiled like the texture function), volume:FILE.raw:WxHxD (RGBA8, over a
     * volume texture) or from-mesh (the glTF input's base colour at the mesh's own uv). */
    const char* color;
    /* Levels of detail (FORMAT.md §7.10): 0 (auto): level 0; for a static
     * height field its native coarser levels (the height field halved, with
     * its own distance map and the exact error: bake/height_field_levels.h;
     * up to 4, each kept while it draws from at most 9/10 of the bytes of
     * the level before); then the base mesh drawn as a plain mesh (a
     * stand-in for when the whole shell is thinner than the error on
     * screen) with its error (the largest offset of the surface drawn), then
     * the base mesh's simplified levels (meshoptimizer, as meso_bake_mesh's
     * auto), each with the base mesh's error plus its own; 1: level 0 only
     * (the file of earlier bakes); N: at most N levels (2: the base mesh
     * only; N >= 3: the base mesh, then native levels, then simplified
     * ones; at most MESO_BAKE_SHELL_MAX_LEVELS). */
    int levels;
    /* The shell also cut into parts (FORMAT.md §7.11, bake/shell_parts.c),
     * so a reader can draw the near end as prisms and the far end as its
     * stand-in: each part's prisms, then its patch of the first stand-in
     * and that patch's own simplifications. 0 = auto (parts of about 1024
     * triangles, when there are stand-ins and at least 2048 triangles), N
     * > 0 = parts of about N triangles (at least 64), -1 = none. */
    int parts;
} meso_bake_shell_options;

#define MESO_BAKE_SHELL_MAX_LEVELS 9 /* in all: level 0, native levels, the base mesh, simplified meshes */

typedef struct meso_bake_shell_report {
    meso_bake_mesh_fixes fixes;
    uint32_t vertices, triangles, boundary_edges;
    double thickness;                   /* mesh units */
    double bbox_diagonal;
    uint32_t prisms, inverted_prisms, undecided_prisms;
    uint64_t offset_self_intersections, offset_base_intersections;
    double thickness_ratio_min, thickness_ratio_mean;
    /* Thickness kept against what the geometry allows (bake/shell_allowed.h:
     * allowed_v = min(requested, half the gap along the normal to the next
     * part of the surface); ratio_v = min(1, |d_v| / allowed_v); an
     * envelope counts each vertex once per layer): */
    double allowed_ratio_min, allowed_ratio_mean;
    uint32_t vertices_below_half_allowed;      /* ratio_v < 0.5 */
    uint32_t vertices_allowed_below_requested; /* allowed_v < requested: the geometry sets the bound */
    uint32_t vertices_regrown;                 /* directors repair shortened and regrow lengthened again
                                                  (bake/shell_regrow.h) */
    uint32_t vertices_bent;                    /* of those still short: directors lengthened or turned (towards
                                                  the normal or their ring) to keep more thickness
                                                  (shell_bend.h) */
    uint32_t vertices_lp, vertices_normal, hybrid_rounds, vertices_shortened;
    uint64_t field_evaluations;
    uint32_t artificial_faces;
    /* With a texture: */
    int density;                        /* 0 height field, 1 density volume */
    uint32_t texture_res[3];
    uint32_t dist_res[3];
    uint64_t dist_solid_cells;
    uint32_t seam_vertices;             /* vertices split off at uv seams */
    int planar_uvs;                     /* 1: the mesh had no uvs (warning); projected */
    /* Wall-clock seconds per stage (in the --report file, not stored in the
     * .meso file, which stays the same bake after bake): load (read, check
     * and fix the mesh; the texture function; with update, OLD and the
     * region), topology (edges, boundary), check (the base's
     * self-intersection test, with more than one thread on its own thread
     * beside field and directors, so not part of their sum; with update,
     * of the moved faces), texture
     * (uvs, seams),
     * field (normals, boundary strip, Barnes-Hut tree), directors (tracing
     * and the hybrid rounds, of which directors_checks in the rounds' exact
     * checks), repair (regrow, bend), validate (the final exact validation),
     * allowed (the allowed thickness, shell_allowed.h), assemble (encoding
     * the output, and waiting for the stand-in levels begun on their own
     * thread once the first side's directors are traced). All layers of an envelope summed. */
    double seconds_load, seconds_topology, seconds_check, seconds_texture, seconds_field, seconds_directors,
        seconds_directors_checks, seconds_repair, seconds_validate, seconds_allowed, seconds_assemble;
    /* With options.update: the vertices the edit moved, and those whose
     * directors were recomputed (within update_radius of a moved face, and
     * the region's growth where the rounds left bad faces with kept
     * corners, shell_update.c). */
    uint32_t vertices_moved, vertices_recomputed;
    double update_radius;
    /* With options.update: how far the farthest vertex moved, and the
     * simplified stand-in levels (after the base mesh's) kept from OLD instead of simplified and
     * measured again (0: built anew; see meso_bake_shell_options.levels). */
    double update_moved_max;
    uint32_t update_levels_kept;
    double update_chain_moved; /* kept levels: how far their base mesh has moved in all, over this and
                                  earlier updates, since they were simplified */
    /* With options.update: how many times a field evaluation opened a cluster of the tree that was
     * built for the recomputed region only (lp_distance.h >>regions). 0 means every evaluation took
     * the whole tree's path, so the directors have the bits a full re-bake's field gives them. */
    uint64_t update_field_unsplit;
    uint32_t parts;       /* parts written (0: none) */
    uint32_t part_levels; /* part levels written, each part's prisms included */
    size_t part_bytes;    /* stored PRTS, PMSH and PVCL payload */
} meso_bake_shell_report;

/* The CLI's defaults (thickness_rel 0.05, p 3, theta 0.5, angle_tol 5,
 * tiling 1, 1, u8 distances). Zero-initialised options mean the same,
 * except theta: 0 is exact summation. */
MESO_BAKE_API meso_bake_shell_options meso_bake_shell_defaults(void);

/* `mesobake shell`: a base mesh plus fold-free directors, validated
 * exactly, as one SHELL object (MESH, SDIR, STHK, and TX2D/TX3D + DIST with
 * a texture). Invalid options are MESO_ERR_INVALID_ARG. */
MESO_BAKE_API meso_result meso_bake_shell(const meso_bake_shell_options* o, meso_bake_output** out,
                                          meso_bake_shell_report* report, meso_error* err);

/* >>cells bake -------------------------------------------------------------- */

#define MESO_BAKE_MAX_TILE_RES 1024u /* --tile-res */
#define MESO_BAKE_MAX_TILES 16384u   /* --tiles (and tiles x tile_res) */

typedef struct meso_bake_cells_options {
    meso_bake_common common;
    const char* input;     /* mesh path, or NULL with `mesh` */
    const meso_mesh* mesh;   /* or, with input NULL: a mesh in memory, copied and checked as a loaded
                                file is (elements, manifold, oriented edges; orientation fixed); META
                                names it "(memory)" with the crc32c of its positions and indices */
    uint32_t tiles;        /* tiles along the longest axis; 0 = 8 (unless cell_size) */
    double cell_size;      /* or: a tile's edge in mesh units (tiles must be 0) */
    uint32_t tile_res;     /* voxels per tile edge; 0 = the tile map's (32 for generators) */
    const char* tile_map;  /* voronoi[:SEEDS[:RNG]] | spheres[:N[:RADIUS]] | FILE.raw:R; NULL = "voronoi" */
    const char* colour;    /* hash[:SEED] | FILE.raw:R | from-mesh[:G]; NULL = "hash" */
    const char* voxelizer; /* auto | parity | vdb | winding; NULL = "auto" */
    int levels;            /* levels of detail, level 0 included (FORMAT.md §7.10): 0 = auto: native
                              coarser levels, the tile map halved each (bake/cells_levels.h), then the
                              base mesh drawn as a plain mesh in the object's place, with its measured error
                              (bake/cells_standin.c), then the base mesh's simplified levels (meshoptimizer,
                              as meso_bake_mesh's auto), each stand-in's error the base's plus its own;
                              1 = level 0 only (no LODS chunk, the file of earlier bakes); 2 = the base mesh
                              only; N = at most N (1..MESO_BAKE_CELLS_MAX_LEVELS): the base mesh, then native
                              levels, then simplified ones */
} meso_bake_cells_options;

#define MESO_BAKE_CELLS_MAX_LEVELS 9 /* in all: level 0, native levels, the base mesh, simplified meshes */

typedef struct meso_bake_cells_report {
    meso_bake_mesh_fixes fixes;
    uint64_t tiles;                       /* tiles in the grid */
    uint32_t tiles_per_axis[3];
    uint32_t tile_res;
    uint32_t split_cells, cells_per_tile, wrapping_cells;
    uint64_t cells_inside, cells_outside, cells_intersected, wrapping_copies;
    uint64_t tiles_outside, tiles_inside, tiles_mixed;
    uint64_t voxels_across;
    const char* voxelizer;                /* the one used: "parity" or "winding" (static) */
    size_t membership_bytes, tile_map_bytes, normal_map_bytes, colour_map_bytes;
    uint64_t memory_estimate;             /* bytes, checked against max_memory */
    uint32_t level_count;                 /* levels written, level 0 included (1: no LODS chunk) */
    double level_error[MESO_BAKE_CELLS_MAX_LEVELS];   /* object units, stored rounded up to f32 */
    uint32_t level_triangles[MESO_BAKE_CELLS_MAX_LEVELS]; /* the mesh each level rasterises (native levels: the base mesh) */
    uint64_t surface_faces;               /* voxel faces of the drawn surface the stand-in error was measured on */
    uint32_t native_levels;               /* levels 1..native_levels are native (tile map halved each), then stand-ins */
} meso_bake_cells_report;

/* All zero (NULL specs mean the defaults above). */
MESO_BAKE_API meso_bake_cells_options meso_bake_cells_defaults(void);

/* `mesobake cells`: the mesh filled with tiled cells, as one CELLS object. */
MESO_BAKE_API meso_result meso_bake_cells(const meso_bake_cells_options* o, meso_bake_output** out,
                                          meso_bake_cells_report* report, meso_error* err);

/* >>frusta bake ------------------------------------------------------------- */

typedef struct meso_bake_frusta_options {
    meso_bake_common common;
    const char* input;          /* skeleton or mesh path (see meso_bake_skeleton_load), or NULL with: */
    const meso_bake_skeleton* skeleton; /* one loaded before, used as it is (not copied; keep it alive
                                           through the call): its file's bytes, name and fit, so the
                                           bake equals one of its path; `tolerance` is the load's */
    double tolerance;           /* mesh input: simplification tolerance; 0 = 1 % of the diagonal */
    double max_joint_angle;     /* degrees; sharper joints become balls; default 150, 0 = no limit */
    int no_fit;                 /* 1: keep node radii at joints (skip the minor-axis fit) */
    int keep_cap_intersections; /* 1: keep the paper's planes where caps intersect */
    const char* relief;         /* a height-field SPEC, or NULL */
    double relief_depth;        /* skeleton units; 0 = a quarter of the mean radius */
    double relief_repeat;       /* tiles around the circumference; default 1 (the colour map's too) */
    const char* relief_color;   /* an 8-bit PNG colour map sampled at the relief coordinates
                                   (FORMAT.md §7.2 kind 4, COLR), with or without a relief; or NULL */
    double twist;               /* degrees of texture twist per unit of skeleton length (default 0):
                                   each segment's twist is twist x its length (a .skel node's
                                   twist=DEG replaces it for its segment); finite, |twist| <=
                                   MESO_BAKE_MAX_TWIST, and no segment over 1000 turns */
    int levels;                 /* levels of detail, level 0 included (FORMAT.md §7.10): 0 = auto (level
                                   0; with a relief, native levels with the relief map halved and the
                                   exact error, bake/height_field_levels.h, up to 4, each kept while it
                                   draws from at most 9/10 of the bytes of the level before; then a
                                   triangle tessellation drawn as a plain mesh with its measured error,
                                   bake/frusta_standin.h; then its simplifications, as meso_bake_mesh's
                                   auto, each with the tessellation's error plus its own), 1 = level 0
                                   only (no LODS chunk, the file of earlier bakes), N = at most N
                                   (1..MESO_BAKE_FRUSTA_MAX_LEVELS; at most 9 are made; N >= 3: the
                                   tessellation, then native levels, then simplified ones) */
} meso_bake_frusta_options;

#define MESO_BAKE_FRUSTA_MAX_LEVELS 16

/* Largest |meso_bake_frusta_options.twist|: 1000 turns per unit length. */
#define MESO_BAKE_MAX_TWIST 360000.0

typedef struct meso_bake_frusta_report {
    meso_bake_skeleton_info skeleton;
    uint32_t segments, joints, branch_points, tips, balls;
    uint32_t ball_joints, sharp_joints, unfitted_joints, degenerate_segments;
    uint32_t cap_intersections_found, cap_intersections_unhandled;
    double fit_error_max, fit_error_mean; /* mesh input: to the mesh; else how far the fit moved radii */
    double seam_gap_max, seam_gap_mean, radius_change_max;
    double relief_depth;                  /* used (0 without relief) */
    /* Levels (FORMAT.md §7.10): */
    uint32_t level_count;      /* levels written, level 0 included (1: no LODS chunk) */
    uint32_t standin_triangles, standin_vertices; /* level 1's mesh (0 without it) */
    size_t standin_bytes;      /* its stored MESH payload */
    double standin_error;      /* its stated error (object units): relief + chord + rounding terms */
    double standin_relief_error, standin_chord_error; /* the first two terms */
    uint32_t native_levels;    /* relief-map levels before the stand-in (bake/height_field_levels.h), lod 1.. */
    uint32_t skeleton_levels;  /* coarser skeletons after them (bake/frusta_skeleton_levels.h) */
    const char* skeleton_levels_stopped; /* why fewer were made (static string), or NULL */
} meso_bake_frusta_report;

/* The CLI's defaults (max_joint_angle 150, relief_repeat 1). Zero-initialised
 * options mean no joint-angle limit and repeat 1. */
MESO_BAKE_API meso_bake_frusta_options meso_bake_frusta_defaults(void);

/* `mesobake frusta`: a skeleton skinned with conical frusta, as one FRUSTA
 * object (SKEL, FRUS, FSEG, BALL, RELF, COLR). */
MESO_BAKE_API meso_result meso_bake_frusta(const meso_bake_frusta_options* o, meso_bake_output** out,
                                           meso_bake_frusta_report* report, meso_error* err);

/* >>pack -------------------------------------------------------------------- */

#define MESO_BAKE_MAX_PACK_INPUTS 4096u

typedef struct meso_bake_pack_options {
    meso_bake_common common;   /* max_memory bounds the inputs' total size (all held until written) */
    const char* const* inputs; /* .meso paths, 1..MESO_BAKE_MAX_PACK_INPUTS, in output order */
    uint32_t input_count;
} meso_bake_pack_options;

typedef struct meso_bake_pack_report {
    uint32_t inputs, objects, chunks;
    uint32_t renamed;  /* objects whose name was taken and got "~k" (warning E3482) */
    uint64_t bytes_in; /* the inputs' total size */
} meso_bake_pack_report;

/* `mesobake pack`: every object of every input, verified in full, into one
 * file; objects numbered 1..N in input order, chunks copied as stored (only
 * their object id changes), names made unique, each input's META and RPRT
 * kept per object in the new ones (bake/bake_pack.c says why). Issue codes:
 *   3480 no inputs or too many          3482 (a warning) a name was taken
 *   3481 an input holds no object       3483 an input has a file-wide chunk
 *                                            other than META, RPRT, OBJT
 * (3484..3489 reserved), and the input's own issue (FORMAT.md codes,
 * prefixed with its file name) when it fails full validation. */
MESO_BAKE_API meso_result meso_bake_pack(const meso_bake_pack_options* o, meso_bake_output** out,
                                         meso_bake_pack_report* report, meso_error* err);

/* >>parsing ----------------------------------------------------------------- */

/* The number syntax of mesobake's options and of the SPECs above, for
 * programs that take the same strings. Each returns 1 and sets *out when
 * the whole string is such a number, else 0 (and leaves *out alone). */
/* "512M", "8G", "1.5GiB" or a byte count (1 .. 2^62) (mesobake --max-memory). */
MESO_BAKE_API int meso_bake_parse_size(const char* s, uint64_t* out);
/* A decimal integer in lo..hi. */
MESO_BAKE_API int meso_bake_parse_long(const char* s, long lo, long hi, long* out);
/* A positive finite number below 1e30 (strtod syntax). */
MESO_BAKE_API int meso_bake_parse_positive(const char* s, double* out);

#ifdef __cplusplus
}
#endif
#endif /* MESO_BAKE_H */
