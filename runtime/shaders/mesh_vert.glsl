// mesh_vert.glsl - base-mesh pass: positions and normals straight from the
// MESH chunk buffer. Prepended: the #version prelude (rt_common.c:
// mesoi_glsl_prelude), instance.glsl (u_model).
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
uniform mat4 u_view;
uniform mat4 u_proj;
out vec3 v_normal;
void main()
{
    instance_begin();
    v_normal = mat3(u_model) * a_normal; // the model matrix is rigid (+ uniform scale)
    gl_Position = u_proj * u_view * u_model * vec4(a_position, 1.0);
}
