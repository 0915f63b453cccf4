// shell_slices_vert.glsl - slice polygons through every prism of a shell
// (MESO_SHELL_SLICES; papers/volume-textures-lp-averaged-shells.md sec. 5,
// "Slice-based direct isosurface rendering", Figure 11), generated from
// gl_VertexID alone like the ray casters' hulls.
//
// Families of slices. The paper slices a hexahedron "in the direction
// closest to the view direction": between the pair of opposite faces that
// faces the eye most. A prism has one such pair (its caps) and, across each
// corner i, the side face opposite i narrowing to the edge at i. So a prism
// is cut along one of four families:
//  - levels T(w) = B + w N at w_m = m / (M - 1), m = 0 .. M-1 (the paper's
//    S_0 = P, S_(M-1) = Q; its "1 - m/M" is read as m/(M-1) so both caps are
//    slices). On a level Phi is affine in (u, v): a slice triangle's
//    interpolated texture coordinates are exact.
//  - lambda_i = c_m = m / M, m = 0 .. M-1 (barycentric coordinate of corner
//    i; lambda_1 = u, lambda_2 = v, lambda_0 = 1 - u - v): the quad between
//    the points c e_i + (1 - c) e_j and c e_i + (1 - c) e_k of the two edges
//    at i, from w = 0 to 1. c = 0 is the side face, c = 1 (the edge at i, a
//    line) is left out. Texture coordinates are affine in (u, v, w), so they
//    are exact at the quad's corners and along its edges; inside, the quad is
//    drawn as two flat triangles while Phi bends it (bilinearly, as much as
//    the directors at its ends differ) - the paper's hexahedron slices, four
//    corners on a "trilinearly distorted cube", are drawn the same way.
// Which family (MESO_SLICE_AXIS_VIEW): the one the view ray through the
// prism's centre crosses most densely, max |rd . grad q| over
// q in {w, lambda_0, lambda_1, lambda_2} (grad through the Jacobian at the
// centre; M slices span each q's range, so this is the most slices per unit
// of ray length, i.e. the finest sampling of alpha along the ray - what the
// alpha test and the two-pass interpolation depend on). "Closest to the view
// direction" by angle alone would pick the side families of a thin prism at
// moderate slopes, where their slices lie a whole edge apart (M slices over
// an edge instead of over the thickness); by density the levels keep a thin
// shell until the view grazes it. Ties keep the levels. Every vertex of a
// prism computes the same choice from the same data.
// MESO_SLICE_AXIS_LEVELS always takes the levels (the layout below with 3
// vertices a slice; the view family's needs 6).
//
// After the slices come each prism's faces: the paper's "faces of the
// hexahedron", the outside sample where a ray enters a prism through one.
// Faces that are slices of the chosen family (the caps of the levels, the
// side face lambda_i = 0) are left out (degenerate).
//
// Order: layer-major (all prisms' nearest slice, then the next, ...), each
// prism's slices from the one nearest the eye, so the depth test rejects
// most hidden slice fragments early.
//
// SLICE_PASS 4 is the full-screen triangle of the composite pass.

uniform int u_slices;      // M >= 2
uniform int u_slice_axis;  // meso_slice_axis: 0 view, 1 levels
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
// The view ray's direction through the prism's centre (object space).
vec3 centre_ray(Prism P)
{
    vec3 c = prism_centroid(P);
    vec4 clip = u_mvp * vec4(c, 1.0);
    vec2 ndc = clip.w > 0.0 ? clip.xy / clip.w : vec2(0.0);
    vec4 a = u_inv_mvp * vec4(ndc, u_depth_ndc.x, 1.0), b = u_inv_mvp * vec4(ndc, u_depth_ndc.y, 1.0);
    return b.xyz / b.w - a.xyz / a.w;
}

// True when the eye sees the prism's levels from above (from the directors'
// side): the view ray through the prism's centre runs against the levels'
// normal.
bool eye_above(Prism P)
{
    vec3 a0 = P.b[0] + 0.5 * P.n[0], a1 = P.b[1] + 0.5 * P.n[1], a2 = P.b[2] + 0.5 * P.n[2];
    vec3 nn = cross(a1 - a0, a2 - a0);
    if (dot(nn, P.n[0] + P.n[1] + P.n[2]) < 0.0)
        nn = -nn;
    return dot(nn, centre_ray(P)) < 0.0;
}

vec2 corner_uv(int c)
{
    return vec2(c == 1 ? 1.0 : 0.0, c == 2 ? 1.0 : 0.0);
}

// Side face `side` of a prism (corners side, side+1 at w = 0 and 1) as two
// triangles; vertex k of triangle half_.
vec3 side_vertex(int side, int half_, int k)
{
    int i = side, j = side == 2 ? 0 : side + 1;
    ivec3 c = half_ == 0 ? ivec3(i, j, j) : ivec3(i, j, i);
    vec3 lv = half_ == 0 ? vec3(0.0, 0.0, 1.0) : vec3(0.0, 1.0, 1.0);
    return vec3(corner_uv(c[k]), lv[k]);
}

// MESO_SLICE_AXIS_LEVELS: M triangles a prism, then 3 side quads.
void levels_vertex(int tri, int k, out int prism, out Prism P, out vec3 q)
{
    int slice_tris = u_slices * u_prism_count;
    if (tri < slice_tris) {
        int layer = tri / u_prism_count;
        prism = tri - layer * u_prism_count;
        P = fetch_prism(prism);
        int m = eye_above(P) ? u_slices - 1 - layer : layer;
        q = vec3(corner_uv(k), float(m) / float(u_slices - 1));
    } else {
        int s = tri - slice_tris;
        prism = s / 6;
        int f = s - 6 * prism, side = f / 2;
        P = fetch_prism(prism);
        q = side_vertex(side, f - 2 * side, k);
    }
}

// The family the view ray crosses most densely: 3 = levels (w), else the
// corner i of lambda_i; *toward: the ray runs up that coordinate.
int view_family(Prism P, out bool toward)
{
    vec3 ju = P.b[1] - P.b[0] + 0.5 * (P.n[1] - P.n[0]);
    vec3 jv = P.b[2] - P.b[0] + 0.5 * (P.n[2] - P.n[0]);
    vec3 jw = (P.n[0] + P.n[1] + P.n[2]) / 3.0;
    // Rows of the inverse Jacobian, times det (a common factor; its sign
    // flips every comparison's direction alike, so it is divided out).
    float det = dot(ju, cross(jv, jw));
    vec3 gu = cross(jv, jw), gv = cross(jw, ju), gw = cross(ju, jv);
    vec3 rd = centre_ray(P) * sign(det);
    float d[4] = float[4](-dot(rd, gu + gv), dot(rd, gu), dot(rd, gv), dot(rd, gw));
    int best = 3;
    for (int f = 0; f < 3; ++f)
        if (abs(d[f]) > abs(d[best]))
            best = f;
    toward = d[best] >= 0.0;
    return best;
}

// Barycentric corner a = c e_i + (1 - c) e_j as (u, v).
vec2 bary_uv(int i, int j, float c)
{
    vec3 l = vec3(0.0);
    l[i] = c;
    l[j] += 1.0 - c;
    return l.yz;
}

// MESO_SLICE_AXIS_VIEW: 2 triangles a slice (levels use the first), then
// 8 face triangles a prism (2 caps, 3 side quads).
void view_vertex(int tri, int k, out int prism, out Prism P, out vec3 q, out bool dead)
{
    int slice_tris = 2 * u_slices * u_prism_count;
    bool toward;
    dead = false;
    if (tri < slice_tris) {
        int layer = tri / (2 * u_prism_count), r = tri - layer * 2 * u_prism_count;
        prism = r >> 1;
        int half_ = r & 1;
        P = fetch_prism(prism);
        int fam = view_family(P, toward);
        int m = toward ? layer : u_slices - 1 - layer;
        if (fam == 3) {
            dead = half_ == 1;
            q = vec3(corner_uv(k), float(m) / float(u_slices - 1));
        } else {
            int j = fam == 2 ? 0 : fam + 1, l = fam == 0 ? 2 : fam - 1;
            float c = float(m) / float(u_slices);
            vec2 a = bary_uv(fam, j, c), b = bary_uv(fam, l, c);
            // Quad (a,0) (b,0) (b,1) (a,1) as two triangles.
            bvec3 at_b = half_ == 0 ? bvec3(false, true, true) : bvec3(false, true, false);
            vec3 lv = half_ == 0 ? vec3(0.0, 0.0, 1.0) : vec3(0.0, 1.0, 1.0);
            q = vec3(at_b[k] ? b : a, lv[k]);
        }
    } else {
        int s = tri - slice_tris;
        prism = s / 8;
        int f = s - 8 * prism;
        P = fetch_prism(prism);
        int fam = view_family(P, toward);
        if (f < 2) { // caps: bottom (w = 0), top
            dead = fam == 3;
            q = vec3(corner_uv(k), float(f));
        } else {
            int side = (f - 2) / 2;
            dead = fam != 3 && fam == (side == 0 ? 2 : side - 1); // the side face opposite corner fam
            q = side_vertex(side, f - 2 - 2 * side, k);
        }
    }
}

void main()
{
    int tri = gl_VertexID / 3, k = gl_VertexID - 3 * tri;
    int prism;
    vec3 q;
    Prism P;
    bool dead = false;
    if (u_slice_axis == 1)
        levels_vertex(tri, k, prism, P, q);
    else
        view_vertex(tri, k, prism, P, q, dead);
    v_prism = prism;
    v_q = q;
    v_stw = vec3(tex_st(P, q.xy), q.z);
    v_pos = phi(P, q);
    // A face the family already draws: all three corners at one point
    // outside the clip volume, nothing rasterised.
    gl_Position = dead ? vec4(2.0, 2.0, 2.0, 1.0) : u_mvp * vec4(v_pos, 1.0);
}
#endif
