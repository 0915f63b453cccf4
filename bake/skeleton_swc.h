/*
 * skeleton_swc.h — skeletons (trees of spheres joined by segments) and the
 * SWC reader.
 *
 * SWC is one node per line, seven whitespace-separated fields:
 *     id type x y z radius parent
 * `id` and `parent` are integers, `parent` = -1 marks a root, `type` is an
 * integer tag (1 soma, 2 axon, 3 dendrite, ... — kept, not interpreted),
 * x y z radius are decimal numbers. '#' starts a comment that runs to the
 * end of the line; blank lines are skipped; line ends may be \n, \r\n or \r.
 * Ids need not be contiguous or sorted, and a parent may come after its
 * child. A file may hold several trees (several roots).
 *
 * Every malformed input is refused with MESO_ERR_CORRUPT (MESO_ERR_IO when
 * the file can't be read, MESO_ERR_OUT_OF_MEMORY) and an issue code in
 * meso_error.code (mesobake prints "E<code>"); the message names the
 * problem and the 1-based line:
 *   3140 no node in the input (empty, or comments only)
 *   3141 a line does not have exactly 7 fields
 *   3142 a field is not a number (or not an integer where one is needed)
 *   3143 a coordinate or radius is NaN or infinite
 *   3144 negative radius
 *   3145 the same id on two lines
 *   3146 parent id that no line defines (or a negative parent other than -1)
 *   3147 the parent links form a cycle (a node is its own ancestor)
 *   3148 the file can't be read, or is too large (more than 2^26 nodes)
 *   3300 a coordinate or radius beyond +-MESO_SKEL_MAX_COORD (1e15): finite
 *        but absurd (squares and float storage would overflow)
 * (The 3140s are the skeleton inputs' range; 3149 is kept for them, and
 * 3300..3349 continue it.)
 *
 * What can be parsed is not always something to draw: a skin of frusta
 * needs a segment with a length and a radius. meso_skeleton_require_drawable
 * refuses the rest, also with MESO_ERR_CORRUPT:
 *   3301 no segment: every tree is a single node (e.g. a one-node file)
 *   3302 every radius is zero: the skin has no surface
 *   3303 no segment has both a length and a radius at one of its ends
 *   3304 (text format) a `twist=` field that is not a number, not finite,
 *        beyond +-MESO_SKEL_MAX_TWIST_DEG, given twice on one line, or on
 *        a root (no segment ends there)
 *
 * The text skeleton format (mesobake's `.skel`, for hand-written and
 * generated skeletons) is one node per line, four or five fields, plus an
 * optional `twist=DEG`:
 *     x y z radius [parent] [twist=DEG]
 * `parent` is the 1-based number of another node line (any order), or 0
 * for a root; without it the node's parent is the node on the previous
 * node line (the first node is a root), so a chain is just its points:
 *     # a bent tube
 *     0 0 0 0.2
 *     0 1 0 0.2
 *     1 2 0 0.15 twist=90   # the segment from node 2 to here twists 90°
 *     -1 2 0 0.1 2    # a branch from node 2
 * `twist=DEG` (one token, no spaces, anywhere on the line) sets the twist
 * of the segment from the node's parent to the node: the relief texture
 * turns by DEG degrees around the segment's axis from the parent's end to
 * this end (relief-mapped-conical-frusta.md §2.3, "adding vθ to the u
 * coordinate"; FORMAT.md's FSEG `twist`, in radians). It replaces, for that
 * segment, what `mesobake frusta --twist` gives by length (frustum_model.h
 * says which sign turns which way). A twist on a zero-length segment is
 * dropped with the segment.
 * Comments, blank lines, line ends and the issue codes are as for SWC
 * (3141: not 4 or 5 fields besides the twist); node ids are the 1-based
 * node numbers.
 */
#ifndef MESO_SKELETON_SWC_H
#define MESO_SKELETON_SWC_H

#include <stddef.h>
#include <stdint.h>

#include "meso_file.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MESO_SKEL_ISSUE_EMPTY 3140u
#define MESO_SKEL_ISSUE_FIELD_COUNT 3141u
#define MESO_SKEL_ISSUE_NOT_A_NUMBER 3142u
#define MESO_SKEL_ISSUE_NON_FINITE 3143u
#define MESO_SKEL_ISSUE_NEGATIVE_RADIUS 3144u
#define MESO_SKEL_ISSUE_DUPLICATE_ID 3145u
#define MESO_SKEL_ISSUE_UNKNOWN_PARENT 3146u
#define MESO_SKEL_ISSUE_CYCLE 3147u
#define MESO_SKEL_ISSUE_UNREADABLE 3148u
#define MESO_SKEL_ISSUE_OUT_OF_RANGE 3300u
#define MESO_SKEL_ISSUE_NO_SEGMENT 3301u
#define MESO_SKEL_ISSUE_NO_RADIUS 3302u
#define MESO_SKEL_ISSUE_NO_SURFACE 3303u
#define MESO_SKEL_ISSUE_TWIST 3304u

/* Largest |twist| of one segment, in degrees (1000 turns: beyond it the
 * runtime's float u loses the texture's precision). */
#define MESO_SKEL_MAX_TWIST_DEG 360000.0

/* Largest magnitude of a coordinate or radius accepted. */
#define MESO_SKEL_MAX_COORD 1e15

/* Largest node count accepted (keeps every index and size in 32 bits). */
#define MESO_SKEL_MAX_NODES (1u << 26)

typedef struct meso_skeleton_node {
    int64_t id;           /* the file's id */
    int32_t type;         /* the file's type tag, not interpreted */
    uint32_t line;        /* 1-based line in the input */
    double pos[3];        /* position (the file's units) */
    double radius;        /* >= 0 (0: the surface pinches to a point here) */
    double twist_deg;     /* text format's `twist=`: degrees over the segment from the parent (0) */
    int has_twist;        /* 1: twist_deg was given (SWC and extracted skeletons: 0) */
    int32_t parent;       /* index into nodes[], -1 for a root */
    uint32_t first_child; /* children of node i: children[first_child .. +child_count) */
    uint32_t child_count;
} meso_skeleton_node;

/* A forest of nodes in input-line order. Arrays are malloc'd and owned by
 * the struct: free with meso_skeleton_free. */
typedef struct meso_skeleton {
    uint32_t node_count;
    uint32_t root_count;
    meso_skeleton_node* nodes;
    uint32_t* children; /* node_count - root_count indices, grouped per parent, in input order */
} meso_skeleton;

typedef enum meso_skeleton_format {
    MESO_SKELETON_SWC = 0, /* id type x y z radius parent */
    MESO_SKELETON_TEXT,    /* x y z radius [parent] [twist=DEG] (above) */
} meso_skeleton_format;

/* Parses SWC text (`len` bytes, need not be NUL-terminated; a NUL byte is
 * data and refused as a non-number). On success fills `out` (caller frees
 * with meso_skeleton_free); on failure `out` is zeroed and `err` (may be
 * NULL) says why. Never reads outside [text, text + len). */
meso_result meso_skeleton_parse_swc(const char* text, size_t len, meso_skeleton* out, meso_error* err);

/* Reads the file at `path` and parses it as above. */
meso_result meso_skeleton_load_swc(const char* path, meso_skeleton* out, meso_error* err);

/* The same for either format. */
meso_result meso_skeleton_parse(const char* text, size_t len, meso_skeleton_format fmt, meso_skeleton* out,
    meso_error* err);
meso_result meso_skeleton_load(const char* path, meso_skeleton_format fmt, meso_skeleton* out, meso_error* err);

/* MESO_OK when `s` has something to draw (codes 3301..3303 above); the
 * message names a line of the input. */
meso_result meso_skeleton_require_drawable(const meso_skeleton* s, meso_error* err);

/* Fills first_child, child_count and children from the nodes' parents
 * (children grouped per parent, in node order); `count` is scratch for
 * node_count entries. */
void meso_skeleton_group_children(meso_skeleton* s, uint32_t* count);

/* Frees the arrays and zeroes the struct. NULL is allowed. */
void meso_skeleton_free(meso_skeleton* s);

#ifdef __cplusplus
}
#endif
#endif /* MESO_SKELETON_SWC_H */
