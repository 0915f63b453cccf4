// raycast_common.glsl - the fragment-side pieces every ray caster shares
// (shells and frusta): the pixel's ray, the hit's exact depth and the work
// counters. Prepended after the kind's common file, which declares
// u_mvp (object -> clip) and u_inv_mvp (clip -> object).
//
// The ray of a pixel starts on the near plane and points to the far plane,
// in object space (runtime/reference/shell_reference.h: the references cast
// the same rays). With MESO_STATS (OpenGL 4.3, ES with fragment storage)
// the shaders count ray-cast fragments, texture samples (g_steps) and hits.

uniform vec4 u_viewport;

#ifdef MESO_STATS
layout(std430, binding = 0) buffer MesoStats {
    uint s_fragments;
    uint s_steps;
    uint s_hits;
};
#endif

int g_steps = 0;

void fragment_ray(out vec3 ro, out vec3 rd)
{
    vec2 ndc = (gl_FragCoord.xy - u_viewport.xy) / u_viewport.zw * 2.0 - 1.0;
    vec4 a = u_inv_mvp * vec4(ndc, -1.0, 1.0);
    vec4 b = u_inv_mvp * vec4(ndc, 1.0, 1.0);
    ro = a.xyz / a.w;
    rd = normalize(b.xyz / b.w - ro);
}

// Window depth of object-space point p.
float window_depth(vec3 p)
{
    vec4 clip = u_mvp * vec4(p, 1.0);
    float ndc_z = clip.z / clip.w;
    return 0.5 * (gl_DepthRange.diff * ndc_z + gl_DepthRange.near + gl_DepthRange.far);
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
