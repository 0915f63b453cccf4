// frusta_vert.glsl - the bounding geometry of frusta objects, from
// gl_VertexID alone (no vertex attributes): 36 vertices = 12 triangles per
// primitive (frustum or ball). The runtime computes each primitive's 8
// corners on the CPU (runtime/rt_frusta.c: the paper's sec. 2.6 obliquely
// cut square pyramid around the cone, enlarged by the relief depth, or a
// box) and stores them after the primitive's parameters in u_prims.
//
// Corners 0-3 lie on the end-0 side, 4-7 on the end-1 side, each four in
// counter-clockwise order seen from outside end 0 (from -axis) in the
// right-handed frame (frame_x, axis, frame_x x axis); the table winds every
// triangle counter-clockwise seen from outside, so the runtime culls front
// faces and gets one fragment per primitive and pixel, camera inside or not.

flat out int v_prim;

const int k_corner[36] = int[36](0, 1, 2, 0, 2, 3,   // end-0 face
                                 4, 6, 5, 4, 7, 6,   // end-1 face
                                 0, 5, 1, 0, 4, 5,   // sides j = 0..3: j, j+1, 4+j+1, 4+j
                                 1, 6, 2, 1, 5, 6,
                                 2, 7, 3, 2, 6, 7,
                                 3, 4, 0, 3, 7, 4);

void main()
{
    instance_begin();
    int local = gl_VertexID / 36;
    int corner = k_corner[gl_VertexID - 36 * local];
    int prim = g_prim_base + local; // the instance's pose slot (instance.glsl)
    vec3 p = texelFetch(u_prims, MESO_FRUSTA_TEXELS * prim + MESO_FRUSTA_CORNER0 + corner).xyz;
    v_prim = prim;
    gl_Position = u_mvp * vec4(p, 1.0);
}
