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

float tex_value(vec3 stw)
{
    if (u_tex_kind == 1)
        return textureLod(u_height, stw.xy, 0.0).r;
    return textureLod(u_volume, stw, 0.0).r;
}

// Outward direction of the solid in texture space (shell_map.h:
// meso_ref_texfn_gradient): central differences one texel apart.
vec3 tex_gradient(vec3 stw)
{
    vec3 d = 1.0 / u_tex_size;
    if (u_tex_kind == 1) {
        float hs = (tex_value(stw + vec3(d.x, 0, 0)) - tex_value(stw - vec3(d.x, 0, 0))) / (2.0 * d.x);
        float ht = (tex_value(stw + vec3(0, d.y, 0)) - tex_value(stw - vec3(0, d.y, 0))) / (2.0 * d.y);
        return vec3(-hs, -ht, 1.0);
    }
    if (u_tex_kind == 2) {
        vec3 g;
        g.x = (tex_value(stw + vec3(d.x, 0, 0)) - tex_value(stw - vec3(d.x, 0, 0))) / (2.0 * d.x);
        g.y = (tex_value(stw + vec3(0, d.y, 0)) - tex_value(stw - vec3(0, d.y, 0))) / (2.0 * d.y);
        g.z = (tex_value(stw + vec3(0, 0, d.z)) - tex_value(stw - vec3(0, 0, d.z))) / (2.0 * d.z);
        return -g;
    }
    return vec3(0.0, 0.0, 1.0);
}

// --- shading ---------------------------------------------------------------

vec2 tex_st(Prism P, vec2 uv)
{
    return P.uv[0] + uv.x * (P.uv[1] - P.uv[0]) + uv.y * (P.uv[2] - P.uv[0]);
}

// The albedo at texture point stw: the COLR colour there, else u_albedo
// (shell_map.h: meso_ref_shell_albedo).
vec3 albedo_at(vec3 stw)
{
    if (u_has_color == 0)
        return u_albedo;
    return textureLod(u_color, stw * u_color_scale, 0.0).rgb;
}

vec3 shade(vec3 albedo, vec3 n, float w, vec3 rd)
{
    n = normalize(n);
    if (dot(n, rd) > 0.0)
        n = -n;
    return albedo * (0.25 + 0.75 * clamp(w, 0.0, 1.0)) * (0.15 + 0.85 * max(0.0, dot(n, u_light_obj)));
}


// n = J^-T g for the Jacobian columns d/du, d/dv, d/dw of a mapping at a
// point: (s,t') = A (u,v) + c  =>  [d/ds d/dt'] = [d/du d/dv] A^-1.
vec3 jacobian_normal(Prism P, vec3 ju, vec3 jv, vec3 jw, vec3 g)
{
    vec2 e1 = P.uv[1] - P.uv[0], e2 = P.uv[2] - P.uv[0];
    float det = e1.x * e2.y - e2.x * e1.y;
    vec3 js = (ju * e2.y - jv * e1.y) / det;
    vec3 jt = (-ju * e2.x + jv * e1.x) / det;
    mat3 J = mat3(js, jt, jw);
    return transpose(inverse(J)) * g;
}
