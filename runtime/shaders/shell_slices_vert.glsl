// shell_slices_vert.glsl - slice polygons through every prism of a shell
// (MESO_SHELL_SLICES; papers/volume-textures-lp-averaged-shells.md sec. 5,
// "Slice-based direct isosurface rendering", Figure 11), generated from
// gl_VertexID alone like the ray casters' hulls.
//
// Slices are the prism's levels T(w) = B + w N at w_m = m / (M - 1),
// m = 0 .. M-1 (the paper's S_0 = P, S_(M-1) = Q; its "1 - m/M" is read as
// m/(M-1) so both caps are slices). On a level the mapping is affine in
// (u, v), so a slice triangle's interpolated texture coordinates are exact:
// no per-fragment inversion. The paper slices "in the direction closest to
// the view direction" of a hexahedron; a shell prism is thin along w, and its
// levels are the only slicing both cheap and exact, so every prism uses them
// (at grazing views the side walls below stand in for the missing slices).
// After the slices come each prism's three side walls (two triangles each):
// the paper's "faces of the hexahedron", the outside sample where a ray
// enters a prism through its side.
//
// Order: layer-major (all prisms' nearest level, then the next, ...), each
// prism's levels from the one nearest the eye, so the depth test rejects
// most hidden slice fragments early.
//
// SLICE_PASS 4 is the full-screen triangle of the composite pass.

uniform int u_slices;      // M >= 2
uniform int u_prism_count;
uniform vec4 u_depth_ndc;  // NDC z of the near plane, of a point between the planes (raycast_common.glsl)

flat out int v_prism;
out vec3 v_q;   // (u, v, w) in the prism
out vec3 v_stw; // texture coordinates (s, t', w)
out vec3 v_pos; // object space

#if SLICE_PASS == 4
void main()
{
    vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2)) * 2.0 - 1.0;
    v_prism = 0;
    v_q = v_stw = v_pos = vec3(0.0);
    gl_Position = vec4(p, 0.0, 1.0);
}
#else
// True when the eye sees the prism's levels from above (from the directors'
// side): the view ray through the prism's centre runs against the levels'
// normal.
bool eye_above(Prism P)
{
    vec3 c = prism_centroid(P);
    vec4 clip = u_mvp * vec4(c, 1.0);
    vec2 ndc = clip.w > 0.0 ? clip.xy / clip.w : vec2(0.0);
    vec4 a = u_inv_mvp * vec4(ndc, u_depth_ndc.x, 1.0), b = u_inv_mvp * vec4(ndc, u_depth_ndc.y, 1.0);
    vec3 rd = b.xyz / b.w - a.xyz / a.w;
    vec3 a0 = P.b[0] + 0.5 * P.n[0], a1 = P.b[1] + 0.5 * P.n[1], a2 = P.b[2] + 0.5 * P.n[2];
    vec3 nn = cross(a1 - a0, a2 - a0);
    if (dot(nn, P.n[0] + P.n[1] + P.n[2]) < 0.0)
        nn = -nn;
    return dot(nn, rd) < 0.0;
}

vec2 corner_uv(int c)
{
    return vec2(c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0);
}

void main()
{
    int tri = gl_VertexID / 3, k = gl_VertexID - 3 * tri;
    int slice_tris = u_slices * u_prism_count;
    int prism;
    vec3 q;
    Prism P;
    if (tri < slice_tris) {
        int layer = tri / u_prism_count;
        prism = tri - layer * u_prism_count;
        P = fetch_prism(prism);
        int m = eye_above(P) ? u_slices - 1 - layer : layer;
        q = vec3(corner_uv(k), float(m) / float(u_slices - 1));
    } else {
        int s = tri - slice_tris;
        prism = s / 6;
        int f = s - 6 * prism, side = f / 2, half_ = f - 2 * side;
        int i = side, j = side == 2 ? 0 : side + 1;
        P = fetch_prism(prism);
        // Quad (i,0) (j,0) (j,1) (i,1) as two triangles.
        ivec3 c = half_ == 0 ? ivec3(i, j, j) : ivec3(i, j, i);
        vec3 lv = half_ == 0 ? vec3(0.0, 0.0, 1.0) : vec3(0.0, 1.0, 1.0);
        q = vec3(corner_uv(c[k]), lv[k]);
    }
    v_prism = prism;
    v_q = q;
    v_stw = vec3(tex_st(P, q.xy), q.z);
    v_pos = phi(P, q);
    gl_Position = u_mvp * vec4(v_pos, 1.0);
}
#endif
