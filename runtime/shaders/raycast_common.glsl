// raycast_common.glsl - the fragment-side pieces every ray caster shares
// (shells and frusta): the pixel's ray, the hit's exact depth and the work
// counters. Prepended after the kind's common file, which declares
// u_mvp (object -> clip) and u_inv_mvp (clip -> object).
//
// The ray of a pixel starts on the near plane and points away from the eye,
// in object space (runtime/reference/shell_reference.h: the references cast
// the same rays). With MESO_STATS (OpenGL 4.3, ES with fragment storage)
// the shaders count ray-cast fragments, texture samples (g_steps) and hits.

uniform vec4 u_viewport;
// The depth convention (meso_rt_draw_desc.depth, .clip_depth): NDC z of the
// near plane, of a finite point between the planes, of the far plane (w = 0
// there when the far plane is at infinity), and 1 for clip depth 0..1.
uniform vec4 u_depth_ndc;

#ifdef MESO_STATS
layout(std430, binding = 0) buffer MesoStats {
    uint s_fragments;
    uint s_steps;
    uint s_hits;
    uint s_rejected;
};
#endif

#ifdef MESO_HULL_REJECT
// Hull rejection (shells, rt_shell.c): the nearest hit depth the draw has
// found per pixel, as window depth bits (complemented under reversed-Z, so
// nearer is smaller either way), cleared to the largest value before the
// draw; image unit 0.
#ifdef GL_ES
layout(r32ui, binding = 0) uniform highp uimage2D u_hits;
#else
layout(r32ui) uniform uimage2D u_hits;
#endif
uniform int u_hull_reject;

uint depth_key(float z)
{
    uint b = floatBitsToUint(z);
    return u_depth_ndc.x > u_depth_ndc.z ? ~b : b;
}

ivec2 hit_texel()
{
    return ivec2(gl_FragCoord.xy - u_viewport.xy);
}

// The fragment's own depth (its hull entry) lies behind a hit already
// found at its pixel: its hit, never nearer than its entry, would fail the
// depth test (rt_shell.c says why, and for which functions). Behind by more
// than 64 ulps: a hit on the face two prisms share is that face's entry
// depth up to rounding (the interpolated depth and the shader's own ray
// differ by a few ulps), and either prism's may be the nearer one.
bool behind_hit()
{
    if (u_hull_reject == 0)
        return false;
    uint best = imageLoad(u_hits, hit_texel()).r;
    return best < 0xFFFFFFFFu - 64u && depth_key(gl_FragCoord.z) > best + 64u;
}
#endif

int g_steps = 0;

// Object-space point at window position `frag` (pixels) and NDC depth z.
vec3 unproject(vec2 frag, float z)
{
    vec2 ndc = (frag - u_viewport.xy) / u_viewport.zw * 2.0 - 1.0;
    vec4 h = u_inv_mvp * vec4(ndc, z, 1.0);
    return h.xyz / h.w;
}

void fragment_ray(out vec3 ro, out vec3 rd)
{
    ro = unproject(gl_FragCoord.xy, u_depth_ndc.x);
    rd = normalize(unproject(gl_FragCoord.xy, u_depth_ndc.y) - ro);
}

// NDC depth <-> window depth under the clip depth mode and glDepthRange.
float ndc_to_window(float ndc_z)
{
    float t = u_depth_ndc.w > 0.5 ? ndc_z : 0.5 * ndc_z + 0.5;
    return gl_DepthRange.near + gl_DepthRange.diff * t;
}

float window_to_ndc(float z)
{
    float t = (z - gl_DepthRange.near) / gl_DepthRange.diff;
    return u_depth_ndc.w > 0.5 ? t : 2.0 * t - 1.0;
}

// True when window depth a is nearer the eye than b (reversed-Z: larger).
bool nearer(float a, float b)
{
    return u_depth_ndc.x > u_depth_ndc.z ? a > b : a < b;
}

// Window depth of object-space point p.
float window_depth(vec3 p)
{
    vec4 clip = u_mvp * vec4(p, 1.0);
    return ndc_to_window(clip.z / clip.w);
}

void write_depth(vec3 p)
{
    gl_FragDepth = window_depth(p);
#ifdef MESO_HULL_REJECT
    if (u_hull_reject != 0) { // the depth the test sees: clamped to the depth range
        float lo = min(gl_DepthRange.near, gl_DepthRange.far), hi = max(gl_DepthRange.near, gl_DepthRange.far);
        imageAtomicMin(u_hits, hit_texel(), depth_key(clamp(gl_FragDepth, lo, hi)));
    }
#endif
}

// --- texture footprints (meso_rt.h meso_texture_filter) -----------------------
//
// What shades a shell's hit (normals from height gradients, colours,
// occlusion) reads the mip level of the pixel's footprint, chosen
// explicitly (textureLod), because implicit derivatives are undefined in
// the ray casters' non-uniform control flow (and a 2x2 quad's neighbours
// may belong to another prism, or miss).
//
// The footprint is the ray differential of Igehy ("Tracing Ray
// Differentials", SIGGRAPH 1999, sec. 3) carried to the surface the texture
// is mapped on: the rays half a pixel either side (in x, in y) meet
// the tangent plane of the surface the texture lies on (for shells the
// layer through the hit, spanned by d/ds and d/dt' of the map), and the
// offsets, taken back through the map's Jacobian, are the texture
// coordinates' derivatives per pixel. The level
// is then OpenGL's isotropic one (OpenGL 4.6 sec. 8.14.1: log2 of the longer
// of the two, in texels), so a grazing view blurs along the shorter axis as
// trilinear filtering does; the layer's plane, not the relief's own facet,
// because the texture is a function over the layer (its filtered levels
// are too) and the facet's normal is what the level is needed for.
uniform int u_mips; // 1: MESO_FILTER_MIPMAP (levels uploaded); 0: level 0 only, as before

// The derivatives per pixel (x, y) of texture coordinates c at the
// object-space hit p, for J = d(object point)/dc there (3 x 3, invertible):
// its first two columns span the surface the texture lies on (shells:
// d/ds, d/dt', d/dw, shell_texfn.glsl tex_jacobian).
// Where the ray through window point px meets the plane through p of
// normal nrm, relative to p; a ray (nearly) parallel to it: a point
// farther than any texture's extent, so the coarsest level.
vec3 plane_offset(vec3 nrm, vec3 p, vec2 px, float far)
{
    vec3 o = unproject(px, u_depth_ndc.x);
    vec3 d = unproject(px, u_depth_ndc.y) - o;
    float den = dot(nrm, d);
    if (abs(den) <= 1e-6 * length(nrm) * length(d))
        return vec3(far, 0.0, 0.0);
    return o + (dot(nrm, p - o) / den) * d - p;
}

// One column of tex_footprint: central differences half a pixel either
// way along `axis` (so a mirrored view gets the mirrored footprint).
vec3 tex_differential(mat3 J, mat3 Ji, vec3 nrm, vec3 p, vec2 axis)
{
    float far = 1e6 * length(J[0]);
    return Ji * (plane_offset(nrm, p, gl_FragCoord.xy + 0.5 * axis, far) -
                 plane_offset(nrm, p, gl_FragCoord.xy - 0.5 * axis, -far));
}

mat2x3 tex_footprint(mat3 J, vec3 p)
{
    vec3 nrm = cross(J[0], J[1]);
    mat3 Ji = inverse(J);
    return mat2x3(tex_differential(J, Ji, nrm, p, vec2(1.0, 0.0)), tex_differential(J, Ji, nrm, p, vec2(0.0, 1.0)));
}

// The level (>= 0) of footprint fp on a texture of `texels` (1 on unused
// axes); 0 without mip levels.
float tex_level(mat2x3 fp, vec3 texels)
{
    if (u_mips == 0)
        return 0.0;
    float rho = max(length(fp[0] * texels), length(fp[1] * texels));
    return rho > 1.0 ? log2(rho) : 0.0;
}


// Counts the fragment and discards it on a miss.
void finish(bool hit)
{
#ifdef MESO_STATS
    atomicAdd(s_fragments, 1u);
    atomicAdd(s_steps, uint(g_steps));
    if (hit)
        atomicAdd(s_hits, 1u);
#endif
    if (!hit)
        discard;
}

#ifdef MESO_HULL_REJECT
// Counts a fragment behind_hit stopped (not as a ray-casting one) and discards it.
void reject()
{
#ifdef MESO_STATS
    atomicAdd(s_rejected, 1u);
#endif
    discard;
}
#endif
