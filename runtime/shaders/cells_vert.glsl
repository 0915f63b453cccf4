// cells_vert.glsl - the base mesh of a cells object, the entry point of its
// rays (cell-based-object-representation.md sec. 3.2.1): object-space position
// and normal for the fragment stage. Prepended: #version, then the
// declarations of u_mvp / u_inv_mvp.
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_normal;
out vec3 v_pos;
out vec3 v_nrm;
void main()
{
    instance_begin();
    v_pos = a_position;
    v_nrm = a_normal;
    gl_Position = u_mvp * vec4(a_position, 1.0);
}
