// Two-sided Lambert with a little ambient; depth is the rasterised depth.
// The runtime prepends the #version prelude (rt_common.c: mesoi_glsl_prelude).
in vec3 v_normal;
uniform vec3 u_light_dir; // world space, towards the light, normalised
uniform vec3 u_albedo;
out vec4 o_color;
void main()
{
    vec3 n = normalize(v_normal);
    float lambert = abs(dot(n, u_light_dir));
    o_color = vec4(u_albedo * (0.15 + 0.85 * lambert), 1.0);
}
