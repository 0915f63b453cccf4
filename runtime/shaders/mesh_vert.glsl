// mesh_vert.glsl - base-mesh pass: positions and normals straight from the
// MESH chunk buffer, and a stand-in's vertex colours (VCOL, FORMAT.md 7.3):
// u_has_color 1: sRGB albedo and linear occlusion (4 components); 2: the
// occlusion alone (1 component, in .r); 0 leaves attribute 2 unread.
// Prepended: the #version prelude (rt_common.c: mesoi_glsl_prelude),
// instance.glsl (u_model).
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
layout(location = 2) in vec4 a_color;
uniform mat4 u_view;
uniform mat4 u_proj;
uniform int u_has_color;
out vec3 v_normal;
out vec4 v_color; // linear albedo (1 when the draw's), occlusion
void main()
{
    instance_begin();
    v_normal = mat3(u_model) * a_normal; // the model matrix is rigid (+ uniform scale)
    v_color = vec4(1.0);
    if (u_has_color == 1) {
        // The sRGB transfer function, exactly as the texture units decode
        // the kinds' SRGB8_ALPHA8 colour maps.
        vec3 c = a_color.rgb;
        v_color = vec4(mix(c / 12.92, pow((c + 0.055) / 1.055, vec3(2.4)), step(vec3(0.04045), c)), a_color.a);
    } else if (u_has_color == 2) {
        v_color.a = a_color.r;
    }
    gl_Position = u_proj * u_view * u_model * vec4(a_position, 1.0);
}
