/*
 * memory_budget.h — limits up front: the bound (`--max-memory`) every bake
 * request is checked against before anything large is allocated, and the
 * estimates it is checked with.
 *
 * A request is refused when its estimate exceeds the budget; nothing has
 * been allocated then, so the command returns at once. Who is refused how:
 *   - a size the command line asks for (cells --tiles / --tile-res, --dist-res,
 *     a built-in texture's RES, a .raw volume's WxHxD) -> MESO_ERR_INVALID_ARG
 *     with code 3400 (exit 1);
 *   - a size an input file dictates (a PNG's header, a skeleton file's
 *     length) -> MESO_ERR_CORRUPT with a code 3401..3403 (exit 3).
 * (A raw tile map or volume whose byte count disagrees with its declared
 * size is refused with its reader's content code, 3152 / 3122, exit 3,
 * before the declared size is allocated: meso_regular_file_size.)
 * Every message names the estimate, the budget and how to raise it.
 *
 * The estimates are upper bounds of the heap a command holds at its peak,
 * written from the allocations of the stages (each function says which);
 * tests/unit/test_memory_budget.c compares them with the buffers a small
 * real run allocates, and the numbers measured against peak RSS are in
 * the comments of each estimate.
 */
#ifndef MESO_MEMORY_BUDGET_H
#define MESO_MEMORY_BUDGET_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "meso_bake.h"
#include "voxelize.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Limit issue codes (meso_error.code), 3400..3449:
 *   3400 a request from the options needs more than the budget (exit 1)
 *   3401 a PNG's header claims more pixels than the budget allows
 *   3402 a skeleton file has more lines (nodes) than the budget allows
 *   (3403..3449 reserved for limits) */
#define MESO_LIMIT_ISSUE_REQUEST 3400u
#define MESO_LIMIT_ISSUE_PNG 3401u
#define MESO_LIMIT_ISSUE_SKELETON 3402u

/* The default budget is this fraction of physical memory (sysconf
 * _SC_PHYS_PAGES x _SC_PAGE_SIZE), and never more than RLIMIT_AS. */
#define MESO_MEMORY_DEFAULT_NUM 1u
#define MESO_MEMORY_DEFAULT_DEN 2u

/* Physical memory in bytes; 0 when the system does not say. */
uint64_t meso_memory_physical(void);

/* Half of physical memory (capped by RLIMIT_AS); 8 GiB when the system does
 * not say. */
uint64_t meso_memory_default_budget(void);

/* Parse SIZE: a plain byte count or a number with a suffix K, M, G, T (powers
 * of 1024, optional "iB"/"B": 512M, 8G, 1.5GiB). Returns 1 and sets *out for
 * a value in 1..2^62 bytes; 0 for anything else (empty, negative, junk,
 * overflow). */
int meso_parse_size(const char* s, uint64_t* out);

/* "9.6 GiB", "512 MiB", "700 bytes" into buf. Returns buf. */
const char* meso_format_size(uint64_t bytes, char* buf, size_t size);

/* Saturating arithmetic for estimates: never wraps, UINT64_MAX is "more
 * than any machine". */
uint64_t meso_size_mul(uint64_t a, uint64_t b);
uint64_t meso_size_add(uint64_t a, uint64_t b);

/* MESO_OK when need <= budget. Otherwise fills err with code `code` and the
 * message "<what> needs about N, more than the memory budget B (--max-memory);
 * raise --max-memory ..." and returns MESO_ERR_INVALID_ARG (code 3400, a
 * request from the options) or MESO_ERR_CORRUPT (any other code: a size an
 * input file dictates). `what` is printf-formatted. */
meso_result meso_budget_check(uint64_t need, uint64_t budget, uint32_t code, meso_error* err, const char* what, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;

/* 1 and the size in bytes when `fp` is a regular file (its length can be
 * compared with what a header or an option says before anything is
 * allocated); 0 for a pipe, a device or when fstat fails. */
int meso_regular_file_size(FILE* fp, uint64_t* size);

/* >>estimates -------------------------------------------------------------- */

/* What a cells bake (bake/bake_cells.c) of mesh `m` over grid `g` holds
 * at its peak: the larger of its two stages.
 *   voxelization and membership: the tile map (2 B per tile-map voxel), its
 *     split-cell labels (4 B), word masks (<= 1 B); the voxelizer's batch of
 *     MIXED tiles (R^3 / 8 B each) and per-thread scratch (4 R^2 + 21 T0 B);
 *     per grid tile the class and merge flag (2 B) and the MEMB index
 *     (1/2 B); per tile near the surface its tags and id (S + 8 B, twice
 *     while the array grows), the merge's copy (S + 8 B) and its record
 *     (S / 4 B); 160 B per triangle (the voxelizer's soup and bins);
 *   chunks and write: tile map and labels, TILE / NRMM / COLR (2 + 4 + 4 B
 *     per voxel) and the writer's copies, the MEMB map three times (map,
 *     chunk, writer's copy), 96 B per triangle (the MESH chunk and its copy);
 * plus 96 MiB for the program, its libraries and allocator overhead. "Near the surface": the
 * tiles within one tile of a triangle's bounding box, summed over triangles
 * (capped at the tile count), an upper bound of PARITY's MIXED tiles and of
 * the tiles the merge may change (WINDING may also mix a tile far from an
 * open mesh, where its winding number crosses 1/2; those are not counted).
 * `splits` is S, the split cells per tile (1 before they are known).
 * threads <= 0: all cores. *near (may be NULL) gets the near-surface count. */
uint64_t meso_cells_estimate(const meso_mesh* m, const meso_voxel_grid* g, uint64_t splits, int threads,
                             uint64_t* near);

/* A texture function of `texels` values (meso_texfn_from_spec): values
 * (4 B), the chunk payload (2 B) and the loader's own buffers (file bytes,
 * floats: 5 B), 11 B per texel. */
uint64_t meso_texture_estimate(uint64_t texels);

/* A distance map of `cells` cells (bake/distance_map.c): the cell maxima
 * (4 B), the mask and its dilation (2 B), squared distances (8 B), the
 * distances (4 B), the payload (<= 4 B) and the writer's copy (<= 4 B). */
uint64_t meso_distmap_estimate(uint64_t cells);

/* A frusta bake of a skeleton file (SWC or text) of `bytes` bytes and
 * `lines` lines (an upper bound of its nodes, hence of its segments): the
 * file (read whole) plus 1 KiB a node: the parsed nodes and their tables
 * (bake/skeleton_swc.c), the frustum model and its chunks with the writer's
 * copy. Measured: 200000-node chains (5.5 and 7.5 MB of SWC) peak at 216 MiB
 * RSS, estimated 301 MiB; the 1.4k-node tests/data/neurom_Neuron.swc peaks
 * at 36 MiB (estimate 98 MiB, most of it the 96 MiB for the program). */
uint64_t meso_skeleton_estimate(uint64_t bytes, uint64_t lines);

/* Bytes and lines ('\n' count, plus one for an unterminated last line) of
 * a file, read in 64 KiB blocks (nothing kept). MESO_ERR_IO when it cannot
 * be opened or read. */
meso_result meso_count_lines(const char* path, uint64_t* bytes, uint64_t* lines, meso_error* err);

#ifdef __cplusplus
}
#endif
#endif /* MESO_MEMORY_BUDGET_H */
