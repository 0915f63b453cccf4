/* shell_color.h — the colour function of a shell (mesobake shell --color;
 * FORMAT.md §7.2 "Shell colour"): RGBA8 texels, sRGB as stored in the
 * chunk COLR, and how they map to the shell's texture space (the CMAP
 * record). Internal to the shell bake.
 *
 * A SPEC is one of:
 *   FILE.png                 a 2D colour in texture space (s, t'), tiled like
 *                            the texture function: any PNG as 8-bit RGBA (the
 *                            stored sRGB values; grey and palette expanded,
 *                            16-bit scaled), the bottom image row at t' = 0
 *   volume:FILE.raw:WxHxD    a 3D colour (s, t', w) for volume shells: RGBA8
 *                            texels, s fastest, then t', then w; needs a
 *                            --texture volume (TX3D)
 *   from-mesh                the input mesh's base colour (glTF material:
 *                            base-colour texture times factor) at the mesh's
 *                            own uv, i.e. at the base point of each texel
 *                            column: colour (s, t')/tiling, not tiled
 */
#ifndef MESO_SHELL_COLOR_H
#define MESO_SHELL_COLOR_H

#include "meso_bake.h"

/* Issue codes (meso_error.code, listed in meso_bake.h). */
#define MESO_COLOR_ISSUE_SPEC 3130u     /* --color SPEC does not parse */
#define MESO_COLOR_ISSUE_FILE 3131u     /* the colour file can not be read (missing, unreadable) */
#define MESO_COLOR_ISSUE_CONTENT 3132u  /* read, but unusable: not a PNG, corrupt, wrong size */
#define MESO_COLOR_ISSUE_MESH 3133u     /* from-mesh: the input has no single usable base colour */

typedef struct mesoi_shell_color {
    uint32_t dims[3];   /* W, H, D (D = 1 for 2D colour) */
    uint8_t* rgba;      /* W*H*D RGBA8 texels (sRGB, straight alpha), s fastest; row 0 is t' = 0 */
    uint32_t mapping;   /* MESO_CMAP_TILED or MESO_CMAP_BASE */
    const char* source; /* "png", "volume" or "from-mesh" (for META) */
} mesoi_shell_color;

/* Whether SPEC is from-mesh (needs the mesh's materials: mesoi_shell_color_from_mesh). */
int mesoi_shell_color_is_from_mesh(const char* spec);

/* A file SPEC (PNG or volume), read within `max_bytes`. Codes 3130..3132,
 * 3401 (a PNG header over the budget), 3400 (a raw volume's size). */
meso_result mesoi_shell_color_load(const char* spec, uint64_t max_bytes, mesoi_shell_color* out, meso_error* err);

/* from-mesh: the one material every triangle of `m` uses. `input` names
 * the file in messages; `has_uvs`: the mesh brought its own uvs (else a
 * texture can not be projected: 3133). Refused with 3133: a non-glTF or
 * in-memory input (no materials), triangles without a material, several
 * different materials, a texture on TEXCOORD_n with n > 0. A material
 * without a texture gives one texel of its factor. */
meso_result mesoi_shell_color_from_mesh(const char* input, const meso_mesh* m, const meso_mesh_materials* mats,
                                        int has_uvs, mesoi_shell_color* out, meso_error* err);

void mesoi_shell_color_free(mesoi_shell_color* c);

/* What a shell's level 0 shows on its base-mesh stand-in and the stand-in's
 * simplifications (standin_appearance.h), as shell_frag.glsl shades a hit
 * seen from outside (from w = 1): over the base point with texture
 * coordinates (s, t') = Σ λ_k uv_k the highest solid w of `fn` (a height
 * field: h(s, t'); a volume: the first α ≥ 1/2 marched down from w = 1 at
 * half its texels, then bisected), the COLR colour there (trilinear in
 * linear light at (s scale[0], t' scale[1], w), wrapping in s and t',
 * clamped in w) and occlusion 0.25 + 0.75 w; a column with no solid shows
 * nothing (the point is left out of the means). `base` has the MESH's
 * uvs. `col` NULL: the shell has no colour, level 0 shows the draw's albedo
 * darkened by the occlusion, and `out` says the occlusion alone
 * (occlusion_only). ctx is filled here and borrowed by `out` with the rest.
 * With `sdir` (the directors, `layers` of them per base vertex: FORMAT.md
 * §7.2 SDIR) the appearance gives normals too (standin_appearance.h): the
 * normal of the surface the prisms map there, Φ(s, t', w) =
 * Σ λ_k (bottom_k + w span_k) (smooth-shells sec. 3.1), taken as the
 * gradient of the texture function (a height field: w − h(s, t'); a
 * volume: 1/2 − α), central differences one texel either side, carried
 * to object space by Φ's inverse transpose Jacobian. */
typedef struct mesoi_shell_colours {
    const meso_mesh* base;
    const struct meso_texfn* fn;
    const mesoi_shell_color* col;
    double scale[2];
    const float* sdir;
    int layers;
} mesoi_shell_colours;
struct mesoi_appearance;
void mesoi_shell_appearance(const meso_mesh* base, const struct meso_texfn* fn, const mesoi_shell_color* col,
                            const double scale[2], const float* sdir, int layers, mesoi_shell_colours* ctx,
                            struct mesoi_appearance* out);

#endif
