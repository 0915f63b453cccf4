/*
 * texture_function.h — the texture function of a shell (FORMAT.md §7.2,
 * "Shell prisms and texture space"): a height field (TX2D) or a density
 * volume (TX3D) over one tile of texture space (s, t, w) ∈ [0,1)² × [0,1].
 *
 * A SPEC names where the function comes from:
 *
 *   height:FILE.png          height field from a PNG: 8-bit files give U8,
 *                            16-bit files U16; grey, or the first channel of
 *                            RGB(A)/palette images. Rows are flipped so that
 *                            the image's bottom row is t = 0 (the usual UV
 *                            convention); no gamma is applied.
 *   volume:FILE.raw:WxHxD    u8 densities, x (s) fastest, then y (t), then z (w)
 *   volume:FILE.vdb[:GRID]   an OpenVDB float grid (default: the first float
 *                            grid), sampled at texel centres over its active
 *                            bounding box at the grid's own voxel resolution
 *                            (longest side capped to 256); see
 *                            meso_vdb_sample_dense for fog volumes vs level
 *                            sets. Stored U16.
 *   bricks[:RES]             running-bond bricks, bevelled mortar, mild
 *                            per-brick height variation; RES² U16 (default 256)
 *   cobble[:RES]             periodic Voronoi stones, domed; RES² U16 (default 256)
 *   ribs[:RES]               cactus ribs: one rib along t per tile with 4 areoles
 *                            on its crest; RES² U16 (default 256)
 *   weave[:RES]              interlaced threads, over/under (overhangs);
 *                            RES × RES × RES/2 U8 (default 128)
 *   cells[:RES]              3D periodic Voronoi cell walls; RES³ U8 (default 64)
 *   boil[:RES]               boiling liquid, bubbles rising through the shell and
 *                            bursting (volume-textures-lp-averaged-shells.md §6);
 *                            RES³ U8 (default 64). Depends on time: it loops with
 *                            a period of 2 s (meso_texfn_period)
 *   icospheres[:RES]         Figure 12's test volume of the Lp-averaged shells
 *                            paper (§5): a sphere with 12 small spheres at the
 *                            vertices of an icosahedron, one per tile, not
 *                            periodic; RES³ U8 (default 64)
 *
 * RES is 8..1024 for height fields and 8..256 for volumes. The built-ins but
 * icospheres tile seamlessly. All are deterministic: they use an integer hash,
 * never libc rand(), and do not depend on the thread count or the platform's
 * libm beyond ordinary rounding.
 *
 * The values held here are exactly what the runtime reads: value / max of
 * the chunk encoding (never the unquantised floats), so the distance map
 * (distance_map.h) bounds the function the runtime will see.
 */
#ifndef MESO_TEXTURE_FUNCTION_H
#define MESO_TEXTURE_FUNCTION_H

#include "meso_bake.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Texture-function issue codes (meso_error.code, also listed in meso_bake.h). */
#define MESO_TEXFN_ISSUE_SPEC 3120u      /* the SPEC does not parse */
#define MESO_TEXFN_ISSUE_FILE 3121u      /* the file can not be read (missing, unreadable) */
#define MESO_TEXFN_ISSUE_CONTENT 3122u   /* the file is read but its content is unusable */
#define MESO_TEXFN_ISSUE_VDB 3123u       /* .vdb input: no such grid, not a float grid, empty */

typedef enum meso_texfn_kind {
    MESO_TEXFN_HEIGHT = 0,  /* TX2D: solid where w <= h(s, t) */
    MESO_TEXFN_DENSITY = 1, /* TX3D: solid where alpha(s, t, w) >= 1/2 */
    MESO_TEXFN_KIND_COUNT
} meso_texfn_kind;

/* A sampled texture function. Zero-initialise; free with meso_texfn_free. */
typedef struct meso_texfn {
    meso_texfn_kind kind;
    uint32_t dims[3];  /* W, H, D (D = 1 for a height field) */
    float* values;     /* W*H*D normalised values in [0, 1], s fastest, then t, then w */
    uint16_t dtype;    /* MESO_DTYPE_U8 or MESO_DTYPE_U16 (the chunk's dtype) */
    void* encoded;     /* W*H*D values of `dtype` (the chunk payload, little-endian) */
    size_t encoded_size; /* bytes */
    char source[16];   /* "height", "volume", "bricks", ... (for reports) */
} meso_texfn;

/* Parse `spec` (syntax above) and build the function. On failure returns an
 * error with a code 3120..3123 and a message naming the spec or file, and
 * leaves *out zeroed. .vdb input needs the OpenVDB adapter (otherwise
 * MESO_ERR_UNSUPPORTED). */
meso_result meso_texfn_from_spec(const char* spec, meso_texfn* out, meso_error* err);

/* The same with a memory budget (memory_budget.h), checked before anything
 * large is allocated: a built-in's RES or a .raw volume's WxHxD over it is
 * MESO_ERR_INVALID_ARG (code 3400, a request from the options); a PNG whose
 * header claims more pixels than it allows is MESO_ERR_CORRUPT (3401). A
 * regular .raw file whose length is not W*H*D exactly is MESO_ERR_CORRUPT
 * (3122), refused before its size is allocated. .vdb input is sampled at
 * most 256 texels a side (64 MiB of floats): bounded by construction. */
meso_result meso_texfn_from_spec_max(const char* spec, uint64_t max_bytes, meso_texfn* out, meso_error* err);

/* The same at `time` seconds: time-dependent built-ins (boil) are sampled
 * at that time; every other SPEC ignores it. The other two calls are this
 * one at time 0. */
meso_result meso_texfn_from_spec_at(const char* spec, double time, uint64_t max_bytes, meso_texfn* out,
                                    meso_error* err);

/* The loop period in seconds of a time-dependent built-in SPEC, 0 for every
 * other SPEC (including unparsable ones). */
double meso_texfn_period(const char* spec);

/* Build a function from normalised values (copied; quantised to `dtype`,
 * and `values` of the result are the quantised ones). dims[2] must be 1 for
 * a height field. */
meso_result meso_texfn_from_values(meso_texfn_kind kind, const uint32_t dims[3], const float* values, uint16_t dtype,
                                   meso_texfn* out, meso_error* err);

void meso_texfn_free(meso_texfn* f);

/* A built-in's underlying continuous function (before sampling and
 * quantisation) at any (s, t, w): height or density; NAN for an unknown
 * name. For tests of periodicity. */
double meso_texfn_builtin_value(const char* name, double s, double t, double w);

/* The filtered function as the runtime samples it (FORMAT.md §7.2): a height
 * field returns h(s, t) (bilinear, wraps; w is ignored), a volume alpha(s, t, w)
 * (trilinear, wraps in s and t, clamps in w). Any real s, t. */
double meso_texfn_sample(const meso_texfn* f, double s, double t, double w);

/* The same in two steps, for callers sampling a lattice: the texels and
 * weight along `axis` (0 s, 1 t, 2 w) at coordinate x, then the value. */
void meso_texfn_axis(const meso_texfn* f, int axis, double x, uint32_t* i0, uint32_t* i1, double* frac);
double meso_texfn_sample_at(const meso_texfn* f, const uint32_t i0[3], const uint32_t i1[3], const double frac[3]);

/* Whether (s, t, w) is solid: w <= h, or alpha >= 1/2; never outside w ∈ [0, 1]. */
int meso_texfn_solid(const meso_texfn* f, double s, double t, double w);

#ifdef __cplusplus
}
#endif
#endif /* MESO_TEXTURE_FUNCTION_H */
