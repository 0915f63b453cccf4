// shell_vert.glsl - generates the rasterised hulls from gl_VertexID alone
// (no vertex attributes), so the host can move base vertices and directors
// every frame without any CPU-side re-triangulation.
//
// Smooth, curved, segment-only: each prism is its convex hull (sec. 4.1; for
// curved shells the hull of the levels the curved prism spans): two
// caps and, per side, the diagonal that makes the side convex ("the fourth
// vertex lies behind the plane of the other three"); 8 triangles = 24
// vertices per prism. Tetra: each prism is three tetrahedra split along the
// diagonals fixed by global vertex order (the smaller index's bottom to the
// larger index's top on every side quad, so neighbours agree); 3 x 4 faces =
// 36 vertices per prism. Every triangle is wound to face away from its
// solid's center, and the runtime culls front faces: one fragment per
// solid per pixel, even with the camera inside the shell.
//
// With hull rejection (MESO_HULL_REJECT, u_hull_reject; rt_shell.c) the
// solid's entry faces are drawn instead (wound towards its center), so a
// fragment's own depth is that of the ray's entry, which no hit of the
// solid is nearer than; a solid reaching the near plane's eye side has
// rays that start inside it, with no entry face: it keeps its exit faces,
// moved onto the near plane (the nearest depth there is), and the
// fragment shader finds the entry itself as before. With the walk (smooth
// shells, u_walk; runtime/rt_prism_walk.c) the sides two prisms share are
// left out: a fragment comes only where the ray enters the shell's volume.

flat out int v_prism;
flat out int v_tet;
#ifdef MESO_HULL_REJECT
uniform int u_hull_reject;
uniform int u_near; // 0: no prism of the draw reaches the near plane's eye side (rt_shell.c)
uniform int u_no_bottom; // 1: the bottom caps are never entered first (runtime/rt_bottom_caps.c)
uniform vec4 u_depth_ndc; // raycast_common.glsl
#if MESO_TECHNIQUE == 0
flat out int v_walk;
#endif

// Whether a hull with corners X reaches the eye's side of the near plane:
// clip z below (reversed-Z: above) u_depth_ndc.x * w.
bool reaches_near(vec3 X[6], int count)
{
    float sgn = u_depth_ndc.x > u_depth_ndc.z ? -1.0 : 1.0;
    bool near_side = false;
    for (int c = 0; c < 6; ++c) {
        if (c >= count)
            break;
        vec4 h = u_mvp * vec4(X[c], 1.0);
        near_side = near_side || sgn * (h.z - u_depth_ndc.x * h.w) < 0.0;
    }
    return near_side;
}

bool prism_reaches_near(Prism P)
{
    vec3 X[6];
    for (int c = 0; c < 6; ++c)
        X[c] = corner_pos(P, c);
    return reaches_near(X, 6);
}
#endif

void main()
{
    instance_begin();
#if MESO_TECHNIQUE == 2
    const int per = 36;
#else
    const int per = 24;
#endif
    int prism = gl_VertexID / per;
    int local = gl_VertexID - prism * per;
    int face = local / 3;
    int k = local - face * 3;
    Prism P = fetch_prism(prism);
#if MESO_TECHNIQUE != 2
    P = hull_prism(P, hull_levels(P));
#endif
    ivec3 tri;
    vec3 center;
    v_tet = 0;
#if MESO_TECHNIQUE == 2
    int tet = face / 4;
    ivec4 T = tet_corners(P, tet);
    tri = tet_face(T, face - tet * 4);
    center = 0.25 * (corner_pos(P, T.x) + corner_pos(P, T.y) + corner_pos(P, T.z) + corner_pos(P, T.w));
    v_tet = tet;
#else
    tri = hull_face(P, face);
    center = prism_centroid(P);
#endif
    vec3 p0 = corner_pos(P, tri.x), p1 = corner_pos(P, tri.y), p2 = corner_pos(P, tri.z);
    // Wind away from the center (counter-clockwise seen from outside);
    // entry faces: towards it.
    bool inward = false, near_side = false;
#ifdef MESO_HULL_REJECT
    if (u_hull_reject != 0) {
        if (u_near != 0) { // the solid is the hull of its corners
#if MESO_TECHNIQUE == 2
            vec3 X[6];
            for (int c = 0; c < 4; ++c)
                X[c] = corner_pos(P, T[c]);
            near_side = reaches_near(X, 4);
#else
            near_side = prism_reaches_near(P);
#endif
        }
        inward = !near_side;
    }
#endif
    if ((dot(cross(p1 - p0, p2 - p0), center - p0) > 0.0) != inward) {
        vec3 s = p1;
        p1 = p2;
        p2 = s;
    }
    vec3 p = k == 0 ? p0 : (k == 1 ? p1 : p2);
    v_prism = prism;
    gl_Position = u_mvp * vec4(p, 1.0);
#ifdef MESO_HULL_REJECT
    if (near_side)
        gl_Position.z = u_depth_ndc.x * gl_Position.w;
#if MESO_TECHNIQUE == 0
    // With the walk a side shared with a neighbour is crossed from prism to
    // prism, never entered from outside the shell: not drawn (outside the
    // clip volume). A prism at the near plane keeps all its faces and does
    // not walk (its rays start inside it: every such prism on a pixel has a
    // fragment of its own), so its neighbours keep the sides they share
    // with it, where rays from it enter them.
    v_walk = u_walk != 0 && !near_side ? 1 : 0;
    if (u_no_bottom != 0 && face == 0) // near_side is false: u_near is 0
        gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    if (v_walk != 0 && face >= 2) {
        int next = side_neighbour(prism, (face - 2) / 2);
        if (next >= 0 && (u_near == 0 || !prism_reaches_near(fetch_prism(next))))
            gl_Position = vec4(2.0, 2.0, 2.0, 1.0);
    }
#endif
#endif
}
