/*
 * cell_reference.h — the exact CPU reference for cell-based objects
 * (cell-based-object-representation.md §3.2; FORMAT.md §7.2 kind 3, §7.8):
 * first hit, specular self-reflection with N bounces and refraction, by an
 * exact voxel traversal in double precision. libmeso's GL ray tracer
 * (runtime/rt_cells.c, shaders/cells_frag.glsl) implements the same rules
 * and is measured against this file; slow and simple on purpose.
 *
 * >>the solid (FORMAT.md: "a renderer draws the voxels of split cells
 * tagged INSIDE and treats everything else as empty")
 * Object voxel (i, j, k), 0 <= i < T0 R (likewise j, k), is SOLID iff
 *     s = TILE[(i mod R) + R ((j mod R) + R (k mod R))] != 0   and
 *     tag(tile (i / R, j / R, k / R), s) == INSIDE              (MEMB decoded)
 * and then it is the closed cube origin + [i, i+1] x [j, j+1] x [k, k+1] h.
 * The solid is the union of those cubes; nothing exists outside the grid.
 * The base mesh plays no part in the reference: it is where libmeso's rays
 * start (§3.2.1), and what differs because of that is measured.
 *
 * >>traversal (replaces Algorithm 3.1's linear + binary search: exact)
 * A ray p(s) = o + s u, u unit, s the distance, walks the voxels it passes
 * in order (Amanatides-Woo), tile by tile: the outer walk visits tiles
 * (a tile of class OUTSIDE is crossed in one step when looking for solid:
 * Algorithm 3.2's empty-tile skipping; a tile of class INSIDE whose tile map
 * has no empty voxel is crossed in one step when looking for empty:
 * Algorithm 3.3's full-tile skipping), the inner walk the tile's voxels.
 * Skipping changes the cost, never the answer. Ties (the ray through an
 * edge or corner) step the lowest axis first (x before y before z).
 * The walk is the merge of the per-axis sequences of grid-plane crossings
 * ordered by (s, axis), each crossing's s computed as
 * (origin_a + x h - o_a) / u_a (x the plane's integer grid coordinate), so
 * a skip lands exactly where the voxel walk would.
 * A search "for solid" from voxel V0 ends at the first voxel V on the walk
 * that is SOLID (V0 itself included: then s = 0 and there is no face): the
 * hit is the point where the ray enters V, s_hit, and the face crossed
 * there, with unit normal f = -sgn(u_a) e_a (a the axis stepped: f points
 * back towards the ray, out of the solid). A search "for empty" ends at the
 * first non-SOLID voxel, which may be a voxel beyond the grid: the exit
 * point, the last SOLID voxel and f = +sgn(u_a) e_a (out of the solid,
 * along the ray). A search for solid that starts beyond the grid jumps to
 * where the ray enters the grid box (the walk's first voxel inside it);
 * rays that leave the grid box (or never enter it) without an end: no hit.
 *
 * >>first hit (pixel rays)
 * The pixel ray is mesoi_ref_pixel_ray's (near plane to far plane); the
 * search for solid starts at the near plane, in the voxel there (the
 * voxel whose closed-open box [x, x + 1) h contains it; possibly beyond the
 * grid, and then the walk starts where the ray enters the grid box, so a
 * SOLID voxel on the grid's boundary is hit on its face like any other). A
 * near plane inside a SOLID voxel is a hit at that point with f = -u (the
 * camera is inside the solid); such an h0 has no face and its secondary
 * ray is not traced (REFLECT and REFRACT take env of it, as for B = 0).
 * Hits beyond the far plane are misses. Depth: mesoi_ref_depth of the hit
 * point; hit as in shell_reference.h; normal: the shading normal n below
 * (it faces the ray's side of the face hit: n . f > 0).
 *
 * >>normals and shading
 * At a hit in SOLID voxel V (tile-map voxel v): m = the NRMM normal of v
 * (FORMAT.md decoder, unit). The shading normal n is m if m . f > 0, else f
 * (the normal map may disagree with the voxel face; the face wins, so
 * lighting never comes from inside). Colour of a hit:
 *     shade = srgb_to_linear(COLR[v].rgb / 255) (0.15 + 0.85 max(0, n . l))
 * with l the object-space light (ref_common.h), srgb_to_linear the exact
 * sRGB curve (x <= 0.04045: x / 12.92, else ((x + 0.055) / 1.055)^2.4).
 * The albedo of the view is not used: cells carry their colour.
 *
 * >>environment (what reflected and refracted rays see when they leave;
 * the built-in one, used unless the options or libmeso's draw pass their own)
 * env(u), u unit, object space, y up; c = max(u.y, 0), g = max(-u.y, 0):
 *     sky(u)    = (0.95, 0.92, 0.85) (1 - c) + (0.30, 0.50, 0.90) c
 *     ground(u) = (0.42, 0.36, 0.30) + 0.12 sin(12 atan2(u.z, u.x)) sin(12 asin(g))
 *                 (each channel)
 *     env(u)    = u.y >= 0 ? sky(u) : sky(u) (1 - min(1, 8 g)) + ground(u) min(1, 8 g)
 * continuous everywhere (striped ground so refraction shows its bending).
 *
 * >>secondary directions (first a rule, then the fallback)
 * reflect(u, n) = u - 2 (u . n) n.  refract(u, n, eta) (GLSL's: n faces
 * the ray, u . n < 0): k = 1 - eta^2 (1 - (n . u)^2); k < 0 is total
 * internal reflection, else eta u - (eta (n . u) + sqrt k) n.
 * A direction computed with the shading normal that would cross back
 * through the face just hit (it must leave on the side the physics says:
 * a reflection off the outside goes out, f . r > 0; a refraction into the
 * solid goes in, f . t < 0; and likewise from inside) is recomputed with f
 * in place of n. The face-normal direction always satisfies the rule.
 *
 * >>specular self-reflection (mode MESO_REF_CELLS_REFLECT, §3.2.3 Alg. 3.2)
 * k = reflectivity, B = bounces (0..8):
 *     colour = (1 - k) shade(h0); w = k; ray = reflect at h0
 *     for b = 1..B: search the ray for solid from the empty voxel in front
 *         of the face just hit (the ray starts at the hit point);
 *         no hit: colour += w env(u); w = 0; stop.
 *         hit h_b: colour += w (1 - k) shade(h_b); w *= k; ray = reflect at h_b
 *     colour += w env(u of the last ray)
 * So B = 0 is environment mapping at the first hit, B = 1 one traced bounce
 * (the thesis's Figure 3.16 orders 0..3). Depth, hit and normal are h0's.
 *
 * >>refraction (mode MESO_REF_CELLS_REFRACT, §3.2.4 Alg. 3.3)
 * tau = transparency, eta_in = 1 / ior (entering), ior (leaving); the ray
 * refracts at h0 into the solid; then up to B more events: inside, search
 * for empty from the hit voxel; at the exit point the outward face f and
 * m of the last SOLID voxel give n = -(m or f) facing the ray, refract with
 * eta = ior (total internal reflection: reflect, and the ray stays inside,
 * starting from the last SOLID voxel); outside, search for solid from the
 * first empty voxel and refract in again. An event whose search finds
 * nothing ends the path; when the B events are used up the path ends too.
 *     colour = (1 - tau) shade(h0) + tau env(u of the last ray)
 * B counts every event after h0 (exits, re-entries and internal
 * reflections). Every event, h0's included, is "refract, or reflect on
 * total internal reflection": a refraction crosses the face, a reflection
 * stays on its side (so with ior < 1 an entry can reflect, and the path
 * goes on outside, from the empty voxel in front of the face).
 *
 * >>threads: the image never depends on the thread count (pthreads).
 */
#ifndef MESO_CELL_REFERENCE_H
#define MESO_CELL_REFERENCE_H

#include <stdint.h>

#include "meso_file.h"
#include "shell_reference.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A cells object, decoded. Tests may build one by hand (everything below
 * is plain data; meso_ref_cells_free frees the arrays with free()). */
typedef struct meso_ref_cells {
    uint32_t tiles[3];  /* T0, T1, T2 */
    uint32_t res;       /* R */
    uint32_t split_count, cell_count;
    double origin[3];   /* min corner of tile (0, 0, 0) */
    double voxel;       /* h */
    uint32_t* tile;     /* R^3 split ids (TILE widened to u32), x fastest */
    uint32_t* memb;     /* the MEMB words as stored (FORMAT.md 7.2 "Membership":
                         * classes, rank, records), decoded on the fly, so
                         * big bakes cost no T x S array; hand-built objects:
                         * meso_ref_cells_set_tags */
    uint64_t memb_words; /* L = 2 ceil(T / 16) + M W */
    int map_full;       /* 1: no TILE value is 0 (INSIDE tiles are wholly solid) */
    float* normal;      /* R^3 x 3, the NRMM normals decoded (unit) */
    uint8_t* colour;    /* R^3 x 4, COLR */
    /* The mesh's colour grid (TX3D U8 x 4, FORMAT.md 7.2 kind 3), or none
     * (grid[0] 0): G0 x G1 x G2 samples at the centres of equal cells
     * spanning the tile grid's box, decoded to linear RGB. With one, the
     * albedo of a hit p is the grid trilinear at p (sample coordinates
     * clamped to [0, G - 1] per axis) instead of COLR's voxel colour. */
    uint32_t grid[3];
    double* grid_rgb;   /* 3 per sample, x fastest */
} meso_ref_cells;

/* The albedo (linear RGB) of a hit at object-space p in solid voxel v. */
void meso_ref_cells_albedo(const meso_ref_cells* c, const int64_t v[3], const double p[3], double rgb[3]);

/* Read a cells object (kind 3): CELL, TILE, MEMB, NRMM and COLR, after
 * meso_file_check_cells (whose MESO_ERR_CORRUPT and message, naming the
 * chunk, a bad file gets; never a crash). */
meso_result meso_ref_cells_load(meso_file* f, uint32_t object_id, meso_ref_cells* out, meso_error* err);
/* The same for level `lod` of a levelled file (FORMAT.md §7.10: per chunk
 * type the smallest lod >= `lod`; a native coarser level's own chunks). */
meso_result meso_ref_cells_load_level(meso_file* f, uint32_t object_id, uint16_t lod, meso_ref_cells* out,
                                      meso_error* err);
void meso_ref_cells_free(meso_ref_cells* c);

/* Tile t's class (0 OUTSIDE, 1 INSIDE, 2 MIXED) and the tag of split cell
 * s (1..S) in tile t (0 OUTSIDE, 1 INSIDE, 2 INTERSECTED), from c->memb;
 * t = tx + T0 (ty + T1 tz) < T. */
unsigned meso_ref_cells_class(const meso_ref_cells* c, uint64_t t);
unsigned meso_ref_cells_tag(const meso_ref_cells* c, uint64_t t, uint32_t s);

/* For hand-built objects: encodes the dense tags (T x S bytes, tile-major,
 * tags[t S + s - 1], values 0..2) as MEMB words into c->memb (replacing
 * it; a tile is OUTSIDE when all its tags are, INSIDE when all are INSIDE,
 * else MIXED) and sets c->map_full from c->tile. tiles, res, split_count
 * and tile must be set. MESO_ERR_INVALID_ARG for a tag above 2. */
meso_result meso_ref_cells_set_tags(meso_ref_cells* c, const uint8_t* tags);

/* 1 if object voxel (i, j, k) is SOLID (0 outside the grid). */
int meso_ref_cells_solid(const meso_ref_cells* c, int64_t i, int64_t j, int64_t k);

enum { MESO_REF_CELLS_FIRST_HIT = 0, MESO_REF_CELLS_REFLECT = 1, MESO_REF_CELLS_REFRACT = 2 };

typedef struct meso_ref_cells_opts {
    int mode;            /* MESO_REF_CELLS_* */
    int bounces;         /* B above, 0..8 */
    double reflectivity; /* k; 0 means 0.5 */
    double ior;          /* 0 means 1.5 */
    double transparency; /* tau; 0 means 0.7 */
    /* The environment: NULL means meso_ref_cells_env; else env(u, rgb,
     * env_user) with u the object-space unit direction (libmeso's
     * cell_environment cube map is looked up with world-space directions:
     * the same when the model matrix is the identity). */
    void (*env)(const double u[3], double rgb[3], const void* env_user);
    const void* env_user;
} meso_ref_cells_opts;

/* One search (>>traversal). From voxel `start` (which must contain o or
 * have o on its boundary) along unit u for at most s_max: want_solid 1
 * looks for solid, 0 for empty. Returns 1 with *s, the voxel ended in
 * (`voxel`: the SOLID voxel entered, or the empty voxel entered) and
 * `axis` (0..2, the axis stepped; -1 if `start` itself ends the search, s
 * = 0), else 0 (also for a non-finite u, or o 2^40 voxels or more from
 * the grid's origin). `last` (may be NULL) receives the voxel before
 * `voxel` (`start` when axis is -1).
 * `steps` (may be NULL) is incremented per voxel and tile visited. */
int meso_ref_cells_search(const meso_ref_cells* c, const double o[3], const double u[3], const int64_t start[3],
                          double s_max, int want_solid, double* s, int64_t voxel[3], int64_t last[3], int* axis,
                          uint64_t* steps);

/* Test hook: 0 turns the tile skipping off (every voxel walked); default 1.
 * Not thread-safe to change while a render runs. */
extern int meso_ref_cells_skipping;

/* One pixel's path: what meso_ref_cells_render computes per pixel, for the
 * ray o + s u (u unit), 0 <= s <= s_max, light l (object space, unit);
 * opts NULL: first hit; bounces clamped to 0..8 (the render refuses others). */
typedef struct meso_ref_cells_path {
    int hit;            /* 0: the ray hits nothing (then nothing below is set) */
    int events;         /* secondary events traced (0..B) */
    double p[9][3];     /* p[0] the hit h0, p[e] event e's point */
    double n[9][3];     /* the shading normal at each (REFRACT: facing the ray) */
    double dir[9][3];   /* the ray leaving p[e] (dir[events] is the last ray; zero in FIRST_HIT) */
    int64_t voxel[9][3]; /* the SOLID voxel of each (REFRACT exits: the last SOLID voxel) */
    double s0;          /* h0's distance along u */
    double rgb[3];      /* the colour */
} meso_ref_cells_path;

void meso_ref_cells_trace(const meso_ref_cells* c, const double o[3], const double u[3], double s_max,
                          const double light[3], const meso_ref_cells_opts* opts, meso_ref_cells_path* out);

/* The environment colour (>>environment). */
void meso_ref_cells_env(const double u[3], double rgb[3]);

/* Render W x H (v->width, v->height) with the rules above into out
 * (shell_reference.h's conventions; v->threads as there). */
meso_result meso_ref_cells_render(const meso_ref_cells* c, const meso_ref_view* v, const meso_ref_cells_opts* o,
                                  meso_ref_image* out);

#ifdef __cplusplus
}
#endif
#endif /* MESO_CELL_REFERENCE_H */
