/*
 * mesh_guard.h — the check every mesh file passes before a third-party
 * reader (OpenMesh, Draco) sees it.
 *
 * The readers trust their input: OpenMesh drops faces it cannot use without a
 * word (index 0, out of range, a NaN coordinate, a two-corner face), loops
 * forever on a truncated PLY header and allocates whatever a PLY or OFF header
 * claims (2^31 elements: tens of GB). So the bytes are scanned first, per
 * format, by this pure C code over a buffer (fuzzed by
 * tests/fuzz/fuzz_mesh_*.c), and a file is handed on only when
 *   - every count a header claims fits in the bytes that follow (using the
 *     smallest encoding of an element) and the memory the reader would need
 *     for it (an estimate, MESO_MESH_GUARD_BYTES_PER_*) fits `max_bytes`;
 *   - every coordinate is a finite float (|v| <= FLT_MAX after conversion);
 *   - every face has >= 3 distinct corners, every index is in range (OBJ:
 *     non-zero, negative ones resolved against the vertices read so far,
 *     positive ones against the whole file, as OpenMesh does; vt/vn too);
 *   - no directed edge a->b is used by two faces (a duplicated face, or more
 *     than two faces on an edge): OpenMesh would refuse that face, add it
 *     on three new vertices and log it (see "Decided" below for what that
 *     cost); here it costs a hash look-up. The reader's own non-manifold check (code 3110, vertices)
 *     still runs after it.
 * What each format gets:
 *   OBJ  v (>= 3 finite numbers), vt/vn (finite), f (>= 3 corners `i`,
 *        `i/t`, `i/t/n`, `i//n`, indices as above). Other lines are ignored
 *        (as OpenMesh does).
 *   OFF  header `[ST][C][N]OFF` (ASCII only: `4OFF`, `nOFF` and `OFF BINARY`
 *        are refused, code 3204), counts `nv nf [ne]` against the file size,
 *        one vertex per line (>= 3 finite numbers), one face per line
 *        (`k i1..ik [colour]`), nothing but blank or comment lines after.
 *   PLY  header bounded to MESO_MESH_GUARD_PLY_HEADER_MAX bytes, every line a
 *        known keyword (ply, format, comment, obj_info, element, property,
 *        end_header), format ascii / binary_little_endian /
 *        binary_big_endian 1.0, known property types; `vertex` needs x y z,
 *        `face` an integer list vertex_indices (or vertex_index). Each
 *        element's count times its smallest size must fit in the bytes left
 *        before the element is walked; list counts likewise. Float
 *        properties of `vertex` must be finite. Only whitespace may follow
 *        the last element.
 *   STL  binary exactly when the size is 84 + 50 n for the n in bytes 80..83
 *        (OpenMesh's own test), else ASCII: solid / facet normal / outer loop
 *        / 3 x vertex / endloop / endfacet ... endsolid. Finite corners, no
 *        two corners of a triangle equal (OpenMesh merges equal positions
 *        and would then drop the face). Edges are not checked (positions,
 *        not indices, name the vertices).
 *   OM   magic "OM", header counts against the file size and the budget
 *        (its chunks are not parsed: the caller's post-read check covers
 *        finite coordinates and index ranges).
 *   DRC  magic "DRACO" and size <= max_bytes / MESO_MESH_GUARD_DRACO_EXPANSION.
 *
 * Decided: OpenMesh stays the reader of valid input (its vertex order, fan
 * triangulation, normals and texture coordinates are what the bakes were
 * made with, and must stay byte-identical). The guard only refuses.
 * Measured (main, CPU time): OpenMesh costs ~3.5 us per face either way
 * (0.64 s for a 180 k-triangle torus OBJ, 1.53 s for 400 k copies of one
 * triangle). The 50 MB OBJ of one repeated triangle is slow because
 * `f 1 2 3` is 8 bytes: 6.5 M faces, each after the first refused and
 * re-added on three new vertices (20 M vertices, 2.8 GB): minutes of wall
 * time on a loaded machine. The guard refuses it at the second face (code
 * 3212, 0.5 s). An honest 50 MB mesh has ~5x fewer faces per byte and
 * reads in seconds (tests/bench/bench_mesh_read.c); the guard costs a
 * fraction of that.
 *
 * Error codes (meso_error.code, exit 3 in mesobake), one per kind of defect;
 * the message names the line (text formats) or the element and byte offset
 * (binary; also in meso_error.offset):
 *   3200 no vertices or no faces (empty, or nothing the format recognises)
 *   3201 the counts would need more memory than max_bytes (or the file is
 *        larger than max_bytes)
 *   3202 a count claims more elements than the file has bytes for; binary
 *        STL size not 84 + 50 n; data ends inside an element
 *   3203 malformed header: OFF counts missing / negative / not integers; PLY
 *        header truncated, too long, unknown keyword or type, bad element or
 *        property line; OM/DRC magic
 *   3204 a format variant the guard does not accept (binary OFF, 4OFF, nOFF,
 *        PLY version other than 1.0, vertex without x y z, face without an
 *        integer index list)
 *   3205 a number that does not parse, or too few numbers on a line
 *   3206 a non-finite coordinate (NaN, Inf, or beyond the float range)
 *   3207 a face with fewer than 3 corners
 *   3208 OBJ index 0
 *   3209 a vertex index out of range (negative in OFF/PLY, beyond the count)
 *   3210 OBJ vt or vn index 0 or out of range
 *   3211 a face that names one vertex twice (STL: two equal corners)
 *   3212 a directed edge used by two faces (duplicated or non-manifold face)
 *   3213 data after the end (non-blank lines after the last OFF face, bytes
 *        after the last PLY element)
 *   3214 ASCII STL structure broken (unexpected keyword, not 3 vertices)
 *   3215 an unknown mesh file extension (path wrapper only)
 */
#ifndef MESO_MESH_GUARD_H
#define MESO_MESH_GUARD_H

#include <stddef.h>
#include <stdint.h>

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum meso_mesh_format {
    MESO_MESH_FORMAT_UNKNOWN = 0,
    MESO_MESH_FORMAT_OBJ,
    MESO_MESH_FORMAT_OFF,
    MESO_MESH_FORMAT_PLY,
    MESO_MESH_FORMAT_STL,
    MESO_MESH_FORMAT_OM,
    MESO_MESH_FORMAT_DRC,
} meso_mesh_format;

enum {
    MESO_MESH_GUARD_EMPTY = 3200,
    MESO_MESH_GUARD_BUDGET = 3201,
    MESO_MESH_GUARD_SIZE = 3202,
    MESO_MESH_GUARD_HEADER = 3203,
    MESO_MESH_GUARD_VARIANT = 3204,
    MESO_MESH_GUARD_NUMBER = 3205,
    MESO_MESH_GUARD_NONFINITE = 3206,
    MESO_MESH_GUARD_FACE_SIZE = 3207,
    MESO_MESH_GUARD_INDEX_ZERO = 3208,
    MESO_MESH_GUARD_INDEX_RANGE = 3209,
    MESO_MESH_GUARD_ATTR_INDEX = 3210,
    MESO_MESH_GUARD_REPEATED_CORNER = 3211,
    MESO_MESH_GUARD_DUPLICATE_EDGE = 3212,
    MESO_MESH_GUARD_TRAILING = 3213,
    MESO_MESH_GUARD_STL_STRUCTURE = 3214,
    MESO_MESH_GUARD_EXTENSION = 3215,
};

/* The default budget (4 GiB) until mesobake has --max-memory. */
#define MESO_MESH_GUARD_DEFAULT_MAX_BYTES (UINT64_C(4) << 30)
/* The memory estimate a count is charged: OpenMesh's kernel, its properties,
 * the arrays handed back and the guard's edge table. Above what was measured:
 * 1.2 M vertices + 0.4 M triangles (a 21 MB OBJ) peaked at 165 MB RSS in
 * mesobake mesh, the estimate says 276 MB. */
#define MESO_MESH_GUARD_BYTES_PER_VERTEX 128u
#define MESO_MESH_GUARD_BYTES_PER_TRIANGLE 256u
#define MESO_MESH_GUARD_PLY_HEADER_MAX 65536u
#define MESO_MESH_GUARD_DRACO_EXPANSION 16u

/* What the guard counted (vertices, polygons, the triangles they fan into). */
typedef struct meso_mesh_guard_stats {
    uint64_t vertices;
    uint64_t faces;
    uint64_t triangles;
} meso_mesh_guard_stats;

/* The format named by the path's extension (case-insensitive). */
meso_mesh_format meso_mesh_format_from_path(const char* path);
const char* meso_mesh_format_name(meso_mesh_format format);

/* Check `size` bytes (no terminator needed; never read beyond) as `format`.
 * max_bytes 0 means MESO_MESH_GUARD_DEFAULT_MAX_BYTES. MESO_OK, or
 * MESO_ERR_CORRUPT with a code above (MESO_ERR_OUT_OF_MEMORY when the
 * guard's own edge table cannot be allocated). stats may be NULL. */
meso_result meso_mesh_guard_check(meso_mesh_format format, const uint8_t* data, size_t size, uint64_t max_bytes,
                                  meso_mesh_guard_stats* stats, meso_error* err);

/* Read `path` (refusing a file larger than max_bytes before reading it) and
 * check it by its extension; messages start with the path. MESO_ERR_IO
 * (code 5001) when it cannot be read. */
meso_result meso_mesh_guard_check_file(const char* path, uint64_t max_bytes, meso_mesh_guard_stats* stats,
                                       meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_MESH_GUARD_H */
