// shell_common.glsl - shared by the shell vertex and fragment shaders.
// The runtime prepends "#version" (and ES precisions), "#define MESO_TECHNIQUE n"
// (0 smooth, 1 curved, 2 tetra, 3 segment only, 4 slices: shell_slices_*.glsl)
// and, where stats are counted (OpenGL 4.3+, ES with fragment storage), MESO_STATS.
// Every function mirrors runtime/reference/shell_map.c (double precision)
// operation by operation; see runtime/reference/shell_map.h for the maths
// and FORMAT.md sec. 7.2 for texture space.

uniform samplerBuffer u_verts;  // 2 texels per vertex: (bottom.xyz, s), (top.xyz, t)
uniform usamplerBuffer u_index; // 3 per triangle
// u_mvp, u_inv_mvp: instance.glsl
uniform float u_uv_scale;
#if defined(MESO_HULL_REJECT) && MESO_TECHNIQUE == 0
// The walk (runtime/rt_prism_walk.c): per prism (as drawn), the prisms
// across its sides 0..2 (side k: corners k, k + 1), -1 for none; u_walk 0:
// every prism draws all its entry faces.
uniform highp isamplerBuffer u_adj;
uniform int u_walk;
int side_neighbour(int prism, int side)
{
    return texelFetch(u_adj, 3 * prism + side).r;
}
#endif

struct Prism {
    vec3 b[3]; // bottom vertices (w = 0)
    vec3 n[3]; // directors: top = b + n
    vec2 uv[3];
    uint id[3]; // global vertex indices (for consistent tetra diagonals)
};

Prism fetch_prism(int f)
{
    Prism P;
    for (int k = 0; k < 3; ++k) {
        uint i = texelFetch(u_index, 3 * f + k).r;
        vec4 lo = texelFetch(u_verts, 2 * int(i));
        vec4 hi = texelFetch(u_verts, 2 * int(i) + 1);
        P.b[k] = lo.xyz;
        P.n[k] = hi.xyz - lo.xyz;
        P.uv[k] = vec2(lo.w, hi.w) * u_uv_scale;
        P.id[k] = i;
    }
    // A triangle whose texture coordinates have no area (a mesh without
    // uvs) uses its barycentrics instead: (0,0), (1,0), (0,1) (FORMAT.md sec. 7.2).
    vec2 e1 = P.uv[1] - P.uv[0], e2 = P.uv[2] - P.uv[0];
    if (abs(e1.x * e2.y - e2.x * e1.y) < 1e-12) {
        P.uv[0] = vec2(0.0, 0.0);
        P.uv[1] = vec2(1.0, 0.0);
        P.uv[2] = vec2(0.0, 1.0);
    }
    return P;
}

// Curved shells leave their prism: Phi_c(u,v,w) = Phi(u,v,wbar) with wbar
// outside [0,1] (sec. 3.2). A conservative range of wbar over the prism
// (shell_map.h: meso_curved_wbar_range, derived there term by term), so the
// rasterised hull B + lo N .. B + hi N contains the whole curved prism.
vec2 curved_wbar_range(Prism P)
{
    vec3 m[3];
    for (int k = 0; k < 3; ++k)
        m[k] = normalize(P.n[k]);
    float E = 0.0;
    for (int lev = 0; lev < 2; ++lev) {
        float wp = lev == 0 ? 0.25 : 0.75;
        for (int i = 0; i < 3; ++i) {
            int j = i == 2 ? 0 : i + 1;
            vec3 e = (P.b[j] + wp * P.n[j]) - (P.b[i] + wp * P.n[i]);
            for (int l = 0; l < 3; ++l)
                E = max(E, abs(dot(e, m[l])));
        }
    }
    float cmin = 1.0;
    for (int i = 0; i < 3; ++i)
        cmin = min(cmin, length(0.5 * (m[i] + m[i == 2 ? 0 : i + 1])));
    vec3 ms = m[0] + m[1] + m[2];
    float msl = length(ms);
    float nmin = 1e30;
    for (int k = 0; k < 3; ++k)
        nmin = min(nmin, msl > 0.0 ? dot(P.n[k], ms) / msl : 0.0);
    if (!(cmin > 1e-6 && nmin > 0.0))
        return vec2(-1.0, 2.0);
    float K = E * (0.25 + 8.0 / (27.0 * cmin)) / nmin;
    return vec2(min(0.25 - K, 0.0), max(0.75 + K, 1.0));
}

// The levels the hull spans: the prism's own [0, 1], or for curved shells
// the range its Coons patches reach (curved_wbar_range).
vec2 hull_levels(Prism P)
{
#if MESO_TECHNIQUE == 1
    return curved_wbar_range(P);
#else
    return vec2(0.0, 1.0);
#endif
}

// The prism whose convex hull is rasterised and clipped against: its
// levels r.x .. r.y (hull_levels).
Prism hull_prism(Prism P, vec2 r)
{
    for (int k = 0; k < 3; ++k) {
        P.b[k] = P.b[k] + r.x * P.n[k];
        P.n[k] = (r.y - r.x) * P.n[k];
    }
    return P;
}

// The smooth mapping Phi(u, v, w) (shell_map.h: meso_phi).
vec3 phi(Prism P, vec3 q)
{
    float t = 1.0 - q.x - q.y;
    return t * P.b[0] + q.x * P.b[1] + q.y * P.b[2] + q.z * (t * P.n[0] + q.x * P.n[1] + q.y * P.n[2]);
}

vec3 corner_pos(Prism P, int c) // c: 0..2 bottom, 3..5 top
{
    return c < 3 ? P.b[c] : P.b[c - 3] + P.n[c - 3];
}

vec3 prism_centroid(Prism P)
{
    return (P.b[0] + P.b[1] + P.b[2]) / 3.0 + (P.n[0] + P.n[1] + P.n[2]) / 6.0;
}

// Triangle `face` (0..7) of the prism's hull (sec. 4.1), as corner indices (not
// yet wound; callers wind it away from the centroid).
ivec3 hull_face(Prism P, int face)
{
    if (face == 0)
        return ivec3(0, 2, 1);
    if (face == 1)
        return ivec3(3, 4, 5);
    int side = (face - 2) / 2, half_ = (face - 2) - 2 * side;
    int i = side, j = side == 2 ? 0 : side + 1;
    // Quad b_i b_j t_j t_i: split along b_i-t_j when t_i lies behind the
    // plane of (b_i, b_j, t_j) seen from outside, else along b_j-t_i.
    vec3 bi = P.b[i], bj = P.b[j], ti = P.b[i] + P.n[i], tj = P.b[j] + P.n[j];
    vec3 nrm = cross(bj - bi, tj - bi);
    if (dot(nrm, prism_centroid(P) - bi) > 0.0)
        nrm = -nrm;
    if (dot(nrm, ti - bi) <= 0.0)
        return half_ == 0 ? ivec3(i, j, j + 3) : ivec3(i, j + 3, i + 3);
    return half_ == 0 ? ivec3(i, j, i + 3) : ivec3(j, j + 3, i + 3);
}

// The three tetrahedra of a prism with diagonals fixed by global vertex
// order (a < b < c): {a0,b0,c0,c1}, {a0,b0,b1,c1}, {a0,a1,b1,c1}. On every
// side quad the diagonal runs from the smaller index's bottom to the larger
// index's top, so adjacent prisms split their shared quad the same way.
ivec4 tet_corners(Prism P, int tet)
{
    int a = 0, b = 1, c = 2, t;
    if (P.id[a] > P.id[b]) { t = a; a = b; b = t; }
    if (P.id[b] > P.id[c]) { t = b; b = c; c = t; }
    if (P.id[a] > P.id[b]) { t = a; a = b; b = t; }
    if (tet == 0)
        return ivec4(a, b, c, c + 3);
    if (tet == 1)
        return ivec4(a, b, b + 3, c + 3);
    return ivec4(a, a + 3, b + 3, c + 3);
}

// Face f of a tetrahedron omits its corner f.
ivec3 tet_face(ivec4 T, int f)
{
    if (f == 0)
        return ivec3(T.y, T.z, T.w);
    if (f == 1)
        return ivec3(T.x, T.w, T.z);
    if (f == 2)
        return ivec3(T.x, T.y, T.w);
    return ivec3(T.x, T.z, T.y);
}
