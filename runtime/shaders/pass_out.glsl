// pass_out.glsl - what a fragment writes in each pass (meso_rt_draw_desc.pass,
// meso_rt.h meso_rt_pass), shared by every kind. The runtime prepends
// "#define MESO_PASS n" (and, forward with a hook, "#define MESO_HOOK 1" and
// the host's meso_shade) to every fragment shader, and this file after the
// kind's common files (rt_common.c mesoi_frag_sources):
//  MESO_PASS 0 forward: o_color at location 0, the kind's built-in shading or
//                       the host's meso_shade;
//            1 depth:   no colour output; the kinds skip their normal and
//                       shading code (#if MESO_PASS != MESO_PASS_DEPTH) and
//                       write only the exact depth;
//            2 G-buffer: location 0 albedo (rgb linear, a the built-in
//                       occlusion factor), location 1 the world-space unit
//                       normal as n * 0.5 + 0.5 (a = 1).
// The object -> world matrix is a similarity (rt_common.c refuses others), so
// mat3(u_model) turns object-space normals into world-space ones up to scale,
// mirrored models included: the inverse transpose of s R is R / s.

#define MESO_PASS_FORWARD 0
#define MESO_PASS_DEPTH 1
#define MESO_PASS_GBUFFER 2

// u_model (object -> world, of the draw or of the instance) comes from
// instance.glsl, which precedes this file.

#if MESO_PASS == MESO_PASS_FORWARD
layout(location = 0) out vec4 o_color;
#elif MESO_PASS == MESO_PASS_GBUFFER
layout(location = 0) out vec4 o_albedo;
layout(location = 1) out vec4 o_normal;
#endif

// The unit normal facing against ray direction rd.
vec3 facing(vec3 n, vec3 rd)
{
    n = normalize(n);
    return dot(n, rd) > 0.0 ? -n : n;
}

// The built-in occlusion of shells and relief frusta: darker deeper in the layer.
float occlusion(float w)
{
    return 0.25 + 0.75 * clamp(w, 0.0, 1.0);
}

vec3 world_normal(vec3 n_obj)
{
    return normalize(mat3(u_model) * n_obj);
}

vec3 world_point(vec3 p_obj)
{
    return (u_model * vec4(p_obj, 1.0)).xyz;
}

// From the hit towards the eye, for a ray of object-space direction rd.
vec3 world_view(vec3 rd_obj)
{
    return -normalize(mat3(u_model) * rd_obj);
}

// The pass's outputs at a hit: `builtin` the kind's built-in colour (forward
// without a hook), albedo and occlusion, n_world the unit shading normal
// facing the viewer, p_world and v_world as meso_shade takes them.
void emit(vec3 builtin, vec3 albedo, float occ, vec3 n_world, vec3 p_world, vec3 v_world)
{
#if MESO_PASS == MESO_PASS_FORWARD
#ifdef MESO_HOOK
    o_color = vec4(meso_shade(albedo * occ, n_world, p_world, v_world), 1.0);
#else
    o_color = vec4(builtin, 1.0);
#endif
#elif MESO_PASS == MESO_PASS_GBUFFER
    o_albedo = vec4(albedo, occ);
    o_normal = vec4(n_world * 0.5 + 0.5, 1.0);
#endif
}

// emit for a ray caster's object-space hit p, normal n facing against rd.
void emit_obj(vec3 builtin, vec3 albedo, float occ, vec3 n, vec3 p, vec3 rd)
{
    emit(builtin, albedo, occ, world_normal(n), world_point(p), world_view(rd));
}
