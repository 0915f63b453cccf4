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
};
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
