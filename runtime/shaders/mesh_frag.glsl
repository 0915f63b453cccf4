// Two-sided Lambert with a little ambient; depth is the rasterised depth.
// A stand-in with vertex colours (VCOL) is shaded as the kind it stands in
// for shades its hits: the albedo (the VCOL's, or the draw's when it holds
// the occlusion alone) times the occlusion times the Lambert term; without
// them the draw's albedo, occlusion 1.
// The runtime prepends the #version prelude (rt_common.c: mesoi_glsl_prelude),
// instance.glsl (u_mvp, u_inv_mvp, u_model of the draw or the instance),
// raycast_common.glsl (for the pixel's ray: the view direction and the world
// point the shading hook takes) and pass_out.glsl (rt_mesh.c).
in vec3 v_normal;
in vec4 v_color;
uniform vec3 u_light_dir; // world space, towards the light, normalised
uniform vec3 u_albedo;
uniform int u_has_color;
void main()
{
    instance_begin();
#if MESO_PASS != MESO_PASS_DEPTH
    vec3 n = normalize(v_normal);
    float lambert = abs(dot(n, u_light_dir));
    vec3 ro, rd;
    fragment_ray(ro, rd);
    vec3 v = world_view(rd);
    vec3 p = world_point(unproject(gl_FragCoord.xy, window_to_ndc(gl_FragCoord.z)));
    vec3 albedo = u_has_color == 1 ? v_color.rgb : u_albedo;
    float occ = u_has_color != 0 ? v_color.a : 1.0;
    emit(albedo * occ * (0.15 + 0.85 * lambert), albedo, occ, dot(n, v) < 0.0 ? -n : n, p, v);
#endif
}
