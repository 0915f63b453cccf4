// shell_texfn.glsl - the texture function of a shell (FORMAT.md sec. 7.2) and
// its shading, shared by the ray casters (shell_frag.glsl) and the slice
// renderer (shell_slices_frag.glsl). Prepended after shell_common.glsl (and
// raycast_common.glsl); mirrors runtime/reference/shell_map.c.

uniform int u_tex_kind; // 0 none (all solid), 1 height field, 2 density volume
uniform sampler2D u_height;
uniform sampler3D u_volume;
uniform vec3 u_tex_size;   // texels of the texture function (1 on unused axes)
// u_light_obj: instance.glsl
uniform vec3 u_albedo;
// Colour (FORMAT.md sec. 7.2 "Shell colour"): COLR as an SRGB8_ALPHA8 3D
// texture (depth 1 for 2D colour; fetches are linear), bilinear/trilinear at
// level 0 like the texture function, repeating in s and t', clamped in w,
// looked up at the hit's texture point times the CMAP scale (u_color_scale.z = 1).
uniform int u_has_color;
uniform sampler3D u_color;
uniform vec3 u_color_scale;

// --- texture function (FORMAT.md sec. 7.2) -------------------------------------

bool solid(vec3 stw)
{
    if (u_tex_kind == 1)
        return stw.z <= textureLod(u_height, stw.xy, 0.0).r;
    if (u_tex_kind == 2)
        return textureLod(u_volume, stw, 0.0).r >= 0.5;
    return true;
}

// --- filtered for the pixel's footprint (raycast_common.glsl tex_footprint) ---
//
// The search (solid) reads level 0: the distance map bounds that level
// only (shared/notes/lod-anchors.md, "Textures and volumes"). What shades
// the hit - the normal from the height gradient, the colour, the occlusion
// term's w - reads the mip level of the pixel's footprint.

// Columns d/ds, d/dt', d/dw (object space) of a mapping whose Jacobian
// columns in prism coordinates are ju, jv, jw: (s,t') = A (u,v) + c, so
// [d/ds d/dt'] = [d/du d/dv] A^-1.
mat3 tex_jacobian(Prism P, vec3 ju, vec3 jv, vec3 jw)
{
    vec2 e1 = P.uv[1] - P.uv[0], e2 = P.uv[2] - P.uv[0];
    float det = e1.x * e2.y - e2.x * e1.y;
    vec3 js = (ju * e2.y - jv * e1.y) / det;
    vec3 jt = (-ju * e2.x + jv * e1.x) / det;
    return mat3(js, jt, jw);
}

float tex_value(vec3 stw, float lod)
{
    if (u_tex_kind == 1)
        return textureLod(u_height, stw.xy, lod).r;
    return textureLod(u_volume, stw, lod).r;
}

// Outward direction of the solid in texture space (shell_map.h:
// meso_ref_texfn_gradient): central differences one texel apart at level
// 0, one texel of the level at coarser ones (2^lod finest texels).
vec3 tex_gradient(vec3 stw, float lod)
{
    vec3 d = exp2(lod) / u_tex_size;
    if (u_tex_kind == 1) {
        float hs = (tex_value(stw + vec3(d.x, 0, 0), lod) - tex_value(stw - vec3(d.x, 0, 0), lod)) / (2.0 * d.x);
        float ht = (tex_value(stw + vec3(0, d.y, 0), lod) - tex_value(stw - vec3(0, d.y, 0), lod)) / (2.0 * d.y);
        return vec3(-hs, -ht, 1.0);
    }
    if (u_tex_kind == 2) {
        vec3 g;
        g.x = (tex_value(stw + vec3(d.x, 0, 0), lod) - tex_value(stw - vec3(d.x, 0, 0), lod)) / (2.0 * d.x);
        g.y = (tex_value(stw + vec3(0, d.y, 0), lod) - tex_value(stw - vec3(0, d.y, 0), lod)) / (2.0 * d.y);
        g.z = (tex_value(stw + vec3(0, 0, d.z), lod) - tex_value(stw - vec3(0, 0, d.z), lod)) / (2.0 * d.z);
        return -g;
    }
    return vec3(0.0, 0.0, 1.0);
}

// The level w that shades a hit at texture point stw (the occlusion term
// and shade's depth factor): the hit's own w at level 0; for a height field
// seen from afar, w moved by the filtered height's departure from level
// 0's, so it is the footprint's mean height (and equals w where lod = 0).
float shade_level(vec3 stw, float lod)
{
    if (u_tex_kind != 1 || lod <= 0.0)
        return stw.z;
    return stw.z + textureLod(u_height, stw.xy, lod).r - textureLod(u_height, stw.xy, 0.0).r;
}

// --- shading ---------------------------------------------------------------

vec2 tex_st(Prism P, vec2 uv)
{
    return P.uv[0] + uv.x * (P.uv[1] - P.uv[0]) + uv.y * (P.uv[2] - P.uv[0]);
}

#ifndef MESO_STAGE_VERTEX
// The albedo at texture point stw: the COLR colour there, else u_albedo
// (shell_map.h: meso_ref_shell_albedo), at level `lod` of the colour map;
// albedo_level: the level of footprint fp on it.
vec3 albedo_lod(vec3 stw, float lod)
{
    if (u_has_color == 0)
        return u_albedo;
    return textureLod(u_color, stw * u_color_scale, lod).rgb;
}

float albedo_level(mat2x3 fp)
{
    return u_has_color == 0 ? 0.0 : tex_level(fp, vec3(textureSize(u_color, 0)) * u_color_scale);
}
#endif

vec3 shade(vec3 albedo, vec3 n, float w, vec3 rd)
{
    n = normalize(n);
    if (dot(n, rd) > 0.0)
        n = -n;
    return albedo * (0.25 + 0.75 * clamp(w, 0.0, 1.0)) * (0.15 + 0.85 * max(0.0, dot(n, u_light_obj)));
}


// n = J^-T g for J the map's tex_jacobian (columns d/ds, d/dt', d/dw).
vec3 jacobian_normal(mat3 J, vec3 g)
{
    return transpose(inverse(J)) * g;
}

#ifndef MESO_STAGE_VERTEX
// What shades a hit, all of it filtered for the pixel's footprint
// (raycast_common.glsl tex_footprint). J: tex_jacobian at the hit p
// (object space), stw its texture point, rd the ray.
//  - albedo, n (object space, J^-T of the gradient) and w (shade_level) at
//    the footprint's level: what the G-buffer stores and the shading hook
//    receives (one normal per pixel; a filtered height's normal is flatter
//    than the mean of the normals it averages, the known limit of
//    prefiltered normals);
//  - color, the built-in shading: the mean of shade() over the footprint,
//    because shading is not linear in the normal (a brick's walls turned
//    from the light stay dark in the mean, and vanish from a flattened
//    normal: measured, the prefiltered normal alone left 0.9 of the
//    unfiltered image's error against a supersampled render, tests/gl/
//    test_rt_mips.c). n x n taps on a regular grid over the footprint's
//    parallelogram, n = 2^lod rounded (1 when magnified: exactly the
//    single sample; at most 4), each at level lod - log2 n - 1: at level
//    lod - log2 n a texel spans the taps' spacing, and bilinear filtering
//    spreads a tap over two texels, so the taps' kernels would overlap
//    and blur twice; one level finer they tile the footprint (measured on
//    test_rt_mips's shell, error against the supersampled render as a
//    fraction of the unfiltered one's: 0.72 at lod - log2 n, 0.50 at
//    lod - log2 n - 1). The taps lie on the layer of the hit, not on the
//    relief itself (no parallax or occlusion between them). Only the
//    forward pass's built-in shading uses the colour (the G-buffer and the
//    shading hook take one albedo and normal), so only it pays for taps.
struct Shading {
    vec3 albedo;
    vec3 n;
    float w;
    vec3 color;
};

vec3 tap_color(mat3 J, vec3 q, float lod, float color_lod, vec3 rd)
{
    vec3 n = jacobian_normal(J, tex_gradient(q, lod));
    float w = u_tex_kind == 1 ? textureLod(u_height, q.xy, lod).r : q.z;
    return shade(albedo_lod(q, color_lod), n, w, rd);
}

Shading shading_at(mat3 J, vec3 stw, vec3 p, vec3 rd)
{
    mat2x3 fp = tex_footprint(J, p);
    float lod = tex_level(fp, u_tex_size);
    float color_lod = albedo_level(fp);
    Shading h;
    h.albedo = albedo_lod(stw, color_lod);
    h.n = jacobian_normal(J, tex_gradient(stw, lod));
    h.w = shade_level(stw, lod);
#if !defined(MESO_PASS) || (MESO_PASS == 0 && !defined(MESO_HOOK)) // forward (or a slice pass of its own)
    int taps = lod > 0.0 ? int(min(floor(exp2(lod) + 0.5), 4.0)) : 1;
#else
    int taps = 1;
#endif
    if (taps == 1) {
        h.color = shade(h.albedo, h.n, h.w, rd);
        return h;
    }
    float down = log2(float(taps)) + 1.0;
    vec3 sum = vec3(0.0);
    for (int j = 0; j < taps; ++j)
        for (int i = 0; i < taps; ++i) {
            vec2 o = (vec2(i, j) + 0.5) / float(taps) - 0.5;
            vec3 q = vec3((stw + o.x * fp[0] + o.y * fp[1]).xy, stw.z);
            sum += tap_color(J, q, max(lod - down, 0.0), max(color_lod - down, 0.0), rd);
        }
    h.color = sum / float(taps * taps);
    return h;
}
#endif

