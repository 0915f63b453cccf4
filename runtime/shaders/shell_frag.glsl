// shell_frag.glsl - ray casting one prism (or tetrahedron) per fragment.
//
// Smooth (MESO_TECHNIQUE 0), papers/smooth-and-curved-shell-mapping.md:
//  sec. 4.2 the ray's entry/exit against the prism's hull triangles (entry = the
//       ray origin on the near plane when only the exit is hit: camera
//       inside), mapped to texture space by bisection on w plus the
//       barycentric correspondence;
//  sec. 4.3 march from entry towards exit in texture space; each candidate is
//       mapped back with Phi and, if it is farther from the view ray than the
//       error bound (u_err_scale * w_clip, i.e. error_px pixels), redirected
//       towards the ray x T(w) point (<= 4 corrections);
//  sec. 4.4 step lengths from the distance map (sphere tracing; near the
//       surface at least a quarter of the error bound, see step_radius) and,
//       once the surface is bracketed, bisection on the filtered texture.
// Curved (1), sec. 3.2/sec. 4.5: the hull of the levels the curved prism spans
//       (curved_wbar_range), then the same march in the smooth prism's (u,v,wbar); the
//       texture is looked up at w from the paper's eq. 2, and steps shrink by
//       wbar(u,v,1) - wbar(u,v,0) (the paper's scaled spheres).
// Tetra (2): the baseline - one tetrahedron per fragment, its affine map
//       from world to texture space, a straight march between entry/exit.
// Segment only (3): sec. 4.2 and nothing else (Table 1's first column).
// Depth: the hit's own clip-space depth (sec. 4.3), not the hull's.

flat in int v_prism;
flat in int v_tet;
#if defined(MESO_HULL_REJECT) && MESO_TECHNIQUE == 0
flat in int v_walk; // shell_vert.glsl: 0 for a prism at the near plane
#endif
// Outputs per pass (o_color, o_albedo, o_normal; emit): pass_out.glsl.

// The texture function, tex_st and shade: shell_texfn.glsl.
uniform sampler3D u_dist;
uniform int u_has_dist;
// u_err_scale: instance.glsl
uniform int u_max_steps;
uniform int u_bisect_steps;
uniform int u_segment_steps;
uniform float u_fixed_step;
uniform float u_min_step;

// Sphere-tracing radius at a texture point (a lower bound on the distance
// to the solid), or the fixed step without a distance map. All solid lies
// in the slab 0 <= w <= 1, so a point delta outside it is at least
// sqrt(d^2 + delta^2) from the solid, d the stored bound at the clamped
// point (curved hulls reach far above and below the slab).
//
// Near the surface the map's bound is 0 (a cell that may touch the solid,
// and its neighbours), and sphere tracing would crawl at a quarter texel
// (u_min_step). There the step is at least g_view_floor: a quarter of the
// error bound (error_px / 4 pixels) in texture units at this fragment's
// nearest depth. Such a step can only pass over solid thinner along the ray
// than a quarter pixel's footprint - the grazing tips of bumps, within a
// sub-pixel band of their silhouettes; the bisection afterwards refines every
// hit. Measured: a full pixel misses silhouettes at low resolutions (3% of
// the pixels of tests/gl's sphere), a quarter matches the conservative march
// (tests/gl/test_rt_shell.c) at 2-4x fewer steps (tests/bench).
float g_view_floor = 0.0;

// Returns the step; g_empty is set to the conservative part alone (the
// radius of a ball known to hold no solid, 0 when nothing is known), so a
// march whose remaining chord fits in that ball can stop without sampling.
float g_empty = 0.0;

float step_radius(vec3 stw)
{
    float outside = max(max(stw.z - 1.0, -stw.z), 0.0);
    if (u_tex_kind == 0) {
        g_empty = outside; // all solid: the slab itself, the exact distance
        return max(outside, u_min_step);
    }
    if (u_has_dist == 0) {
        g_empty = outside;
        return max(outside, u_fixed_step);
    }
    float d = textureLod(u_dist, vec3(stw.xy, clamp(stw.z, 0.0, 1.0)), 0.0).r;
    g_empty = sqrt(d * d + outside * outside);
    return max(g_empty, max(u_min_step, g_view_floor));
}

// g_view_floor for a ray segment from world point a to b whose texture-space
// length is tex_len.
void set_view_floor(vec3 a, vec3 b, float tex_len)
{
    float wl = length(b - a);
    float wc = min((u_mvp * vec4(a, 1.0)).w, (u_mvp * vec4(b, 1.0)).w);
    g_view_floor = wl > 0.0 ? 0.25 * u_err_scale * max(wc, 0.0) * tex_len / wl : 0.0;
}

// --- the mappings (shell_map.h) --------------------------------------------

// Barycentrics (u, v) of p projected onto the plane of triangle a0 a1 a2.
vec2 barycentric(vec3 a0, vec3 a1, vec3 a2, vec3 p)
{
    vec3 e1 = a1 - a0, e2 = a2 - a0, d = p - a0;
    float d11 = dot(e1, e1), d12 = dot(e1, e2), d22 = dot(e2, e2);
    float d1 = dot(d, e1), d2 = dot(d, e2);
    float den = d11 * d22 - d12 * d12;
    return vec2(d22 * d1 - d12 * d2, d11 * d2 - d12 * d1) / den;
}

// sec. 4.2: w of a point by bisection on the sign of dot(n(T(w)), p - A0(w)),
// over the hull's levels r widened by a quarter on each side, so points
// just outside the hull still map.
float find_w(Prism P, vec3 p, vec2 r)
{
    float pad = 0.25 * (r.y - r.x);
    float lo = r.x - pad, hi = r.y + pad;
    for (int i = 0; i < u_segment_steps; ++i) {
        float m = 0.5 * (lo + hi);
        vec3 a0 = P.b[0] + m * P.n[0], a1 = P.b[1] + m * P.n[1], a2 = P.b[2] + m * P.n[2];
        if (dot(cross(a1 - a0, a2 - a0), p - a0) > 0.0)
            lo = m;
        else
            hi = m;
    }
    return 0.5 * (lo + hi);
}

vec3 to_texture(Prism P, vec3 p, vec2 r)
{
    float w = find_w(P, p, r);
    vec2 uv = barycentric(P.b[0] + w * P.n[0], P.b[1] + w * P.n[1], P.b[2] + w * P.n[2], p);
    return vec3(uv, w);
}

// A point on the hull, hit through hull face `face` (0: the cap at level
// r.x, 1: the cap at r.y, else a side, -1: not on the hull). On a cap, w is
// the cap's level exactly and no search is needed; elsewhere the sec. 4.2
// bisection runs, and counts as one step.
vec3 hull_point_to_texture(Prism P, vec3 p, int face, vec2 r)
{
    if (face == 0 || face == 1) {
        float w = face == 0 ? r.x : r.y;
        return vec3(barycentric(P.b[0] + w * P.n[0], P.b[1] + w * P.n[1], P.b[2] + w * P.n[2], p), w);
    }
    ++g_steps;
    return to_texture(P, p, r);
}

// Curved shells: Coons(lambda) on T(w') (shell_map.h spells out the construction).
float hermite_edge(vec3 ai, vec3 aj, vec3 mi, vec3 mj, float s)
{
    vec3 e = aj - ai;
    float a = -dot(e, mi), b = -dot(e, mj);
    return s * (1.0 - s) * (a * (1.0 - s) - b * s);
}

float coons(Prism P, float wp, float u, float v)
{
    float lam[3] = float[3](1.0 - u - v, u, v);
    vec3 A[3], m[3];
    for (int k = 0; k < 3; ++k) {
        A[k] = P.b[k] + wp * P.n[k];
        m[k] = normalize(P.n[k]);
    }
    float num = 0.0, den = 0.0;
    for (int i = 0; i < 3; ++i) {
        int j = i == 2 ? 0 : i + 1, k = i == 0 ? 2 : i - 1;
        float wi = lam[i] * lam[i];
        den += wi;
        float sjk = lam[j] + lam[k];
        if (abs(sjk) < 1e-12)
            continue;
        float sig = 1.0 - lam[i];
        vec3 qj = A[i] + sig * (A[j] - A[i]), qk = A[i] + sig * (A[k] - A[i]);
        float hj = hermite_edge(A[i], A[j], m[i], m[j], sig);
        float hk = hermite_edge(A[i], A[k], m[i], m[k], sig);
        vec3 mj = normalize((1.0 - sig) * m[i] + sig * m[j]);
        vec3 mk = normalize((1.0 - sig) * m[i] + sig * m[k]);
        vec3 d = qk - qj;
        float gj = -dot(d, mj), gk = -dot(d, mk);
        float r = lam[k] / sjk, r2 = r * r, r3 = r2 * r;
        float di = (2.0 * r3 - 3.0 * r2 + 1.0) * hj + (r3 - 2.0 * r2 + r) * gj + (-2.0 * r3 + 3.0 * r2) * hk +
                   (r3 - r2) * gk;
        num += wi * di;
    }
    return den > 0.0 ? num / den : 0.0;
}

float curved_wbar(Prism P, float u, float v, float w)
{
    float wp = 0.5 * w + 0.25;
    float t = 1.0 - u - v;
    float len = length(t * P.n[0] + u * P.n[1] + v * P.n[2]);
    return wp + coons(P, wp, u, v) / len;
}

vec3 phi_curved(Prism P, vec3 q)
{
    return phi(P, vec3(q.xy, curved_wbar(P, q.x, q.y, q.z)));
}

// --- shading ---------------------------------------------------------------

// J = dmap/d(s,t',w) (tex_jacobian) by central differences in (u,v,w);
// the normal is J^-T g (jacobian_normal).
mat3 map_jacobian(Prism P, vec3 q, bool curved)
{
    const float h = 1e-3;
    vec3 ju, jv, jw;
    if (curved) {
        ju = (phi_curved(P, q + vec3(h, 0, 0)) - phi_curved(P, q - vec3(h, 0, 0))) / (2.0 * h);
        jv = (phi_curved(P, q + vec3(0, h, 0)) - phi_curved(P, q - vec3(0, h, 0))) / (2.0 * h);
        jw = (phi_curved(P, q + vec3(0, 0, h)) - phi_curved(P, q - vec3(0, 0, h))) / (2.0 * h);
    } else {
        ju = (phi(P, q + vec3(h, 0, 0)) - phi(P, q - vec3(h, 0, 0))) / (2.0 * h);
        jv = (phi(P, q + vec3(0, h, 0)) - phi(P, q - vec3(0, h, 0))) / (2.0 * h);
        jw = (phi(P, q + vec3(0, 0, h)) - phi(P, q - vec3(0, 0, h))) / (2.0 * h);
    }
    return tex_jacobian(P, ju, jv, jw);
}
// The hit's colour, normal and depth term through pass_out.glsl's emit_obj,
// shaded at the level of the pixel's footprint (shell_texfn.glsl
// shading_at). J: tex_jacobian at the hit p, stw its texture point.
void shade_hit(mat3 J, vec3 stw, vec3 p, vec3 rd)
{
    Shading h = shading_at(J, stw, p, rd);
    emit_obj(h.color, h.albedo, occlusion(h.w), facing(h.n, rd), p, rd);
}

// --- rays (fragment_ray, write_depth, finish: raycast_common.glsl) --------

// Ray/triangle (Moller-Trumbore) with a small tolerance; -1 on a miss.
float ray_triangle(vec3 ro, vec3 rd, vec3 p0, vec3 p1, vec3 p2)
{
    vec3 e1 = p1 - p0, e2 = p2 - p0, pv = cross(rd, e2);
    float det = dot(e1, pv);
    if (abs(det) < 1e-20)
        return -1.0;
    float inv = 1.0 / det;
    vec3 tv = ro - p0;
    float u = dot(tv, pv) * inv;
    vec3 qv = cross(tv, e1);
    float v = dot(rd, qv) * inv;
    const float tol = 1e-4;
    if (u < -tol || v < -tol || u + v > 1.0 + tol)
        return -1.0;
    return dot(e2, qv) * inv;
}

// The point of the view ray at level w = q.z, as texture coordinates
// (u, v, w): the ray meets the plane of T(w), and the barycentric
// correspondence gives (u, v) (sec. 3.1). False for a ray parallel to T(w).
bool onto_ray(Prism P, vec3 q, vec3 ro, vec3 rd, out vec3 r)
{
    vec3 a0 = P.b[0] + q.z * P.n[0], a1 = P.b[1] + q.z * P.n[1], a2 = P.b[2] + q.z * P.n[2];
    vec3 nn = cross(a1 - a0, a2 - a0);
    float den = dot(nn, rd);
    r = q;
    if (abs(den) < 1e-12 * length(nn))
        return false;
    vec3 x = ro + (dot(nn, a0 - ro) / den) * rd;
    r = vec3(barycentric(a0, a1, a2, x), q.z);
    return true;
}

#if MESO_TECHNIQUE == 2
// --- tetrahedra ------------------------------------------------------------
void main()
{
#ifdef MESO_HULL_REJECT
    if (behind_hit()) {
        reject();
        return;
    }
#endif
    instance_begin();
    Prism P = fetch_prism(v_prism);
    ivec4 T = tet_corners(P, v_tet);
    vec3 X[4];
    vec3 C[4];
    for (int k = 0; k < 4; ++k) {
        int c = T[k];
        X[k] = corner_pos(P, c);
        C[k] = vec3(P.uv[c < 3 ? c : c - 3], c < 3 ? 0.0 : 1.0);
    }
    vec3 ro, rd;
    fragment_ray(ro, rd);
    float te = 0.0, tx = 1e30;
    for (int f = 0; f < 4; ++f) {
        ivec3 fi = tet_face(ivec4(0, 1, 2, 3), f);
        vec3 a = X[fi.x], n = cross(X[fi.y] - a, X[fi.z] - a);
        if (dot(n, X[f] - a) > 0.0)
            n = -n;
        float den = dot(n, rd), num = dot(n, a - ro);
        if (abs(den) < 1e-20) {
            if (num < 0.0)
                te = 1e30; // parallel and outside
        } else if (den < 0.0) {
            te = max(te, num / den);
        } else {
            tx = min(tx, num / den);
        }
    }
    if (!(te < tx)) {
        finish(false);
        return;
    }
    mat3 M = mat3(X[1] - X[0], X[2] - X[0], X[3] - X[0]);
    mat3 Tm = mat3(C[1] - C[0], C[2] - C[0], C[3] - C[0]);
    if (abs(determinant(M)) < 1e-30 || abs(determinant(Tm)) < 1e-30) {
        finish(false);
        return;
    }
    mat3 Minv = inverse(M);
    vec3 q0 = C[0] + Tm * (Minv * (ro + te * rd - X[0]));
    vec3 q1 = C[0] + Tm * (Minv * (ro + tx * rd - X[0]));
    float len = length(q1 - q0);
    set_view_floor(ro + te * rd, ro + tx * rd, len);
    float f = 0.0, fprev = 0.0;
    bool hit = false, budget_spent = true;
    for (int i = 0; i < u_max_steps; ++i) {
        vec3 q = mix(q0, q1, f);
        ++g_steps;
        if (solid(q)) {
            hit = true;
            break;
        }
        if (f >= 1.0 || len <= 0.0) {
            budget_spent = false;
            break;
        }
        float r = step_radius(q);
        if (g_empty >= (1.0 - f) * len) {
            budget_spent = false; // the rest of the segment lies in an empty ball
            break;
        }
        fprev = f;
        f = min(1.0, f + r / len);
    }
    if (!hit && budget_spent) {
        hit = true; // out of steps: the last sample, as for prisms below
        f = fprev;
    }
    if (hit && f > fprev) {
        float lo = fprev, hi = f;
        for (int i = 0; i < u_bisect_steps; ++i) {
            float m = 0.5 * (lo + hi);
            ++g_steps;
            if (solid(mix(q0, q1, m)))
                hi = m;
            else
                lo = m;
        }
        f = hi;
    }
    if (hit) {
        vec3 q = mix(q0, q1, f);
        vec3 p = ro + (te + f * (tx - te)) * rd;
#if MESO_PASS != MESO_PASS_DEPTH
        shade_hit(M * inverse(Tm), q, p, rd); // world = X0 + J (texture - C0)
#endif
        write_depth(p);
    }
    finish(hit);
}

#else
// --- smooth, curved, segment only ------------------------------------------

// sec. 4.2: where the ray meets the prism's hull (the same triangulation as
// shell_vert.glsl: hull_face of hull_prism, each side split once, by the
// diagonal that makes it convex): entry tmin through hull face fmin, exit
// tmax through fmax (faces 0, 1 the caps at range.x, range.y, then the
// sides' halves); en the exit face's normal. Only when fewer than two faces
// are hit is the origin tested against the faces' planes (camera inside the
// shell: tmin 0, fmin -1). False for a ray that misses or grazes the hull.
bool hull_span(Prism HP, vec3 ro, vec3 rd, out float tmin, out float tmax, out int fmin, out int fmax, out vec3 en)
{
    vec3 c[6];
    for (int k = 0; k < 3; ++k) {
        c[k] = HP.b[k];
        c[k + 3] = HP.b[k] + HP.n[k];
    }
    vec3 cen = prism_centroid(HP);
    vec3 T[24];
    T[0] = c[0], T[1] = c[1], T[2] = c[2];
    T[3] = c[3], T[4] = c[4], T[5] = c[5];
    for (int side = 0; side < 3; ++side) {
        int i = side, j = side == 2 ? 0 : side + 1;
        vec3 bi = c[i], bj = c[j], ti = c[i + 3], tj = c[j + 3];
        vec3 nrm = cross(bj - bi, tj - bi);
        if (dot(nrm, cen - bi) > 0.0)
            nrm = -nrm;
        bool diag_bt = dot(nrm, ti - bi) <= 0.0;
        int k = 6 + 6 * side;
        T[k] = bi, T[k + 1] = bj, T[k + 2] = diag_bt ? tj : ti;
        T[k + 3] = diag_bt ? bi : bj, T[k + 4] = tj, T[k + 5] = ti;
    }
    tmin = 1e30;
    tmax = -1e30;
    fmin = -1;
    fmax = -1;
    en = vec3(0.0);
    int nhit = 0;
    for (int f = 0; f < 8; ++f) {
        float t = ray_triangle(ro, rd, T[3 * f], T[3 * f + 1], T[3 * f + 2]);
        if (t >= 0.0) {
            if (t < tmin) {
                tmin = t;
                fmin = f;
            }
            if (t > tmax) {
                tmax = t;
                fmax = f;
            }
            ++nhit;
        }
    }
    if (nhit < 2 || !(tmin < tmax)) {
        bool origin_inside = true;
        for (int f = 0; f < 8; ++f) {
            vec3 p0 = T[3 * f], nrm = cross(T[3 * f + 1] - p0, T[3 * f + 2] - p0);
            if (dot(nrm, cen - p0) > 0.0)
                nrm = -nrm;
            origin_inside = origin_inside && dot(nrm, ro - p0) <= 0.0;
        }
        if (!origin_inside || nhit < 1)
            return false; // a ray grazing an edge or corner of the hull
        tmin = 0.0; // the ray starts inside the hull (camera inside the shell)
        fmin = -1;
    }
    en = cross(T[3 * fmax + 1] - T[3 * fmax], T[3 * fmax + 2] - T[3 * fmax]);
    return true;
}

#if MESO_TECHNIQUE != 3
// The march through one prism (sec. 4.3, 4.4). True on a hit: hq its
// texture point (u, v, w of the smooth prism), hw the texture function's w
// there. Else `left`: the march went through the whole prism (not out of
// steps), so the walk may go on where the ray leaves it, and q0, q1 are
// the ends of the march's chord; g_no_span: no part of the ray lies in the
// prism.
bool g_no_span = false;
bool cast_prism(Prism P, vec3 ro, vec3 rd, out vec3 hq, out float hw, out bool left, out vec3 cq0, out vec3 cq1)
{
    hq = vec3(0.0);
    hw = 0.0;
    left = false;
    cq0 = cq1 = vec3(0.0);
    vec2 range = hull_levels(P);
    float tmin, tmax;
    int fmin, fmax;
    vec3 en;
    g_no_span = true;
    if (!hull_span(hull_prism(P, range), ro, rd, tmin, tmax, fmin, fmax, en))
        return false;
    vec3 q0 = hull_point_to_texture(P, ro + tmin * rd, fmin, range);
    vec3 q1 = hull_point_to_texture(P, ro + tmax * rd, fmax, range);
    vec2 e1 = P.uv[1] - P.uv[0], e2 = P.uv[2] - P.uv[0];
    const bool curved = MESO_TECHNIQUE == 1;
    vec3 dq = q1 - q0;
    set_view_floor(ro + tmin * rd, ro + tmax * rd, length(vec3(dq.x * e1 + dq.y * e2, dq.z)));
    // The hull is larger than the prism (sides are bilinear, curved prisms
    // are bounded loosely): clip the chord q0 -> q1 to the prism's texture
    // domain, widened by m: a margin for the ray's texture-space path, which
    // bends away from the chord (tests/gl measure no lost hits at 0.02).
    const float m = 0.02; // barycentric / w units
    float wlo = curved ? range.x : -m, whi = curved ? range.y : 1.0 + m;
    {
        float c0[5] = float[5](q0.x + m, q0.y + m, 1.0 + m - q0.x - q0.y, q0.z - wlo, whi - q0.z);
        float c1[5] = float[5](q1.x + m, q1.y + m, 1.0 + m - q1.x - q1.y, q1.z - wlo, whi - q1.z);
        float fa = 0.0, fb = 1.0;
        for (int k = 0; k < 5; ++k) {
            float a = c0[k], b = c1[k] - c0[k];
            if (b == 0.0) {
                if (a < 0.0)
                    fb = -1.0;
            } else if (b > 0.0) {
                fa = max(fa, -a / b);
            } else {
                fb = min(fb, -a / b);
            }
        }
        if (!(fa <= fb))
            return false;
        g_no_span = false;
        vec3 qa = q0 + fa * dq, qb = q0 + fb * dq;
        q0 = qa;
        q1 = qb;
    }
    vec3 q = q0, qprev = q0;
    float wq = q0.z; // texture w (= q.z for smooth shells)
    bool hit = false, budget_spent = true, last_inside = false;
    for (int i = 0; i < u_max_steps; ++i) {
        bool inside = q.x >= -1e-5 && q.y >= -1e-5 && q.x + q.y <= 1.0 + 1e-5;
        float scale = 1.0;
        wq = q.z;
        if (curved && inside) {
            float w0 = curved_wbar(P, q.x, q.y, 0.0), w1 = curved_wbar(P, q.x, q.y, 1.0);
            wq = (q.z - w0) / (w1 - w0); // eq. 2
            scale = clamp(w1 - w0, 0.05, 1.0);
        }
        // Below w = 0 of a smooth prism lies what the base mesh encloses:
        // solid for a height field (w <= h, h >= 0; the reference's solid
        // reaches w = 0 exactly), so a ray that steps across w = 0 between
        // two samples hits there and does not slip into the base mesh.
        inside = inside && (wq >= 0.0 || (u_tex_kind != 2 && !curved)) && wq <= 1.0;
        last_inside = inside;
        vec2 st = tex_st(P, q.xy);
        ++g_steps;
        if (inside && solid(vec3(st, wq))) {
            hit = true;
            break;
        }
        vec3 D = q1 - q;
        float remain = length(vec3(D.x * e1 + D.y * e2, D.z));
        if (remain <= 1e-6) {
            budget_spent = false;
            break;
        }
        float r = step_radius(vec3(st, wq));
        if (g_empty * scale >= remain) {
            budget_spent = false; // the rest of the segment lies in an empty ball
            break;
        }
        float L = min(r * scale, remain);
        vec3 qn = q + D * (L / remain);
        // sec. 4.3: keep the sample within the error bound of the view ray.
        for (int c = 0; c < 4; ++c) {
            vec3 p = phi(P, qn);
            vec4 clip = u_mvp * vec4(p, 1.0);
            vec3 off = (p - ro) - dot(p - ro, rd) * rd;
            if (length(off) <= u_err_scale * clip.w)
                break;
            vec3 target;
            if (!onto_ray(P, qn, ro, rd, target))
                break; // grazing: linear sampling is already right (sec. 4.3)
            vec3 Dn = target - q;
            float ln = length(vec3(Dn.x * e1 + Dn.y * e2, Dn.z));
            if (ln <= 1e-9)
                break;
            qn = q + Dn * min(1.0, L / ln);
        }
        qprev = q;
        q = qn;
    }
    if (!hit && budget_spent && last_inside) {
        // Out of steps inside the shell: the surface is taken to be at the
        // last sample (qprev, the one tested), so a small budget shows as
        // surfaces drawn too high, never as holes onto whatever lies behind.
        hit = true;
        q = qprev;
    }
    if (!hit) {
        left = !budget_spent;
        cq0 = q0;
        cq1 = q1;
        return false;
    }
    // sec. 4.4: bisection between the last empty sample and the first solid one.
    vec3 lo = qprev, hi = q;
    float whi_ = wq;
    for (int i = 0; i < u_bisect_steps; ++i) {
        vec3 mm = 0.5 * (lo + hi);
        vec3 mr;
        if (onto_ray(P, mm, ro, rd, mr))
            mm = mr; // bisect along the ray itself, not the chord in texture space
        float wm = mm.z;
        if (curved) {
            float w0 = curved_wbar(P, mm.x, mm.y, 0.0), w1 = curved_wbar(P, mm.x, mm.y, 1.0);
            wm = (mm.z - w0) / (w1 - w0);
        }
        ++g_steps;
        bool in_ = mm.x >= -1e-5 && mm.y >= -1e-5 && mm.x + mm.y <= 1.0 + 1e-5 && (wm >= 0.0 || (u_tex_kind != 2 && !curved)) &&
                   wm <= 1.0;
        if (in_ && solid(vec3(tex_st(P, mm.xy), wm))) {
            hi = mm;
            whi_ = wm;
        } else {
            lo = mm;
        }
    }
    hq = hi;
    hw = whi_;
    return true;
}
#endif

#if defined(MESO_HULL_REJECT) && MESO_TECHNIQUE == 0
// The side the march's chord q0 -> q1 (texture space) leaves through: the
// corner weight (u, v, 1 - u - v) that falls below 0 first along it (one
// below 0 at q0: at once); -1 none: a cap. Only where exit_side finds no
// crossing at all (rounding on a twisted side).
int chord_side(vec3 q0, vec3 q1)
{
    float c0[3] = float[3](q0.x, q0.y, 1.0 - q0.x - q0.y);
    float c1[3] = float[3](q1.x, q1.y, 1.0 - q1.x - q1.y);
    float first = 1e30;
    int side = -1;
    for (int j = 0; j < 3; ++j) {
        float b = c1[j] - c0[j];
        float f = b < 0.0 && c1[j] < 1e-3 ? -c0[j] / b : 1e30;
        if (f < first) {
            first = f;
            // corner 1's weight (u) gone: side 2; v: side 0; 1 - u - v: side 1
            side = j == 0 ? 2 : (j == 1 ? 0 : 1);
        }
    }
    return side;
}

// The side of P whose neighbour a ray belongs to that was rasterised on P's
// cap but misses P (it grazes the edge two caps share, on the neighbour's
// side): the side across from the corner whose weight is lowest where the
// ray meets the plane of the cap (top or bottom, whichever it meets nearer
// the triangle); -1 if none is near.
int grazed_side(Prism P, vec3 ro, vec3 rd)
{
    int side = -1;
    float best = -0.25;
    for (int lev = 0; lev < 2; ++lev) {
        vec3 q;
        if (!onto_ray(P, vec3(0.0, 0.0, float(lev)), ro, rd, q))
            continue;
        float wgt[3] = float[3](1.0 - q.x - q.y, q.x, q.y);
        int k = 0;
        for (int j = 1; j < 3; ++j)
            if (wgt[j] < wgt[k])
                k = j;
        if (wgt[k] > best) {
            best = wgt[k];
            side = k == 0 ? 1 : (k == 1 ? 2 : 0); // across from corner k
        }
    }
    return side;
}

// Where the ray leaves smooth prism P first after ray parameter t_from: the
// side 0..2 it crosses outwards (side k: corners k, k + 1, the bilinear
// patch B(s, w) = (1 - s)(b_k + w n_k) + s(b_k1 + w n_k1)), or -1 when that
// is a cap (out of the shell, or into what the base mesh encloses) or
// nothing; t_exit its parameter. Exact, not the march's chord (which
// bends in texture space and, near a corner, picked sides the ray never
// crosses): a side is met where the ray and the patch's line at level w
// are coplanar, det(rd, A_k(w) - ro, A_k1(w) - A_k(w)) = 0, a quadratic in
// w; s and t then follow from the two lines' closest points. A crossing
// counts where the ray goes outwards: away from the opposite corner at the
// same level for a side, up through the top cap, down through the bottom.
int exit_side(Prism P, vec3 ro, vec3 rd, float t_from, out float t_exit)
{
    const float tol = 1e-4;
    float best = 1e30;
    int side = -1;
    vec3 up = P.n[0] + P.n[1] + P.n[2];
    for (int lev = 0; lev < 2; ++lev) {
        float w = float(lev);
        vec3 a0 = P.b[0] + w * P.n[0], a1 = P.b[1] + w * P.n[1], a2 = P.b[2] + w * P.n[2];
        vec3 nn = cross(a1 - a0, a2 - a0);
        if (dot(nn, up) < 0.0)
            nn = -nn;
        float den = dot(nn, rd);
        if (lev == 1 ? !(den > 0.0) : !(den < 0.0))
            continue; // not outwards through this cap
        float t = dot(nn, a0 - ro) / den;
        if (!(t > t_from && t < best))
            continue;
        vec2 bc = barycentric(a0, a1, a2, ro + t * rd);
        if (bc.x < -tol || bc.y < -tol || bc.x + bc.y > 1.0 + tol)
            continue;
        best = t;
        side = -1;
    }
    for (int k = 0; k < 3; ++k) {
        int i = k, j = k == 2 ? 0 : k + 1, o = k == 0 ? 2 : k - 1;
        vec3 a0 = P.b[i] - ro, a1 = P.n[i], e0 = P.b[j] - P.b[i], e1 = P.n[j] - P.n[i];
        float c0 = dot(rd, cross(a0, e0));
        float c1 = dot(rd, cross(a0, e1) + cross(a1, e0));
        float c2 = dot(rd, cross(a1, e1));
        float r[2] = float[2](-1.0, -1.0);
        if (abs(c2) <= 1e-7 * (abs(c1) + abs(c0))) {
            if (c1 != 0.0)
                r[0] = -c0 / c1;
        } else {
            float disc = c1 * c1 - 4.0 * c2 * c0;
            if (disc >= 0.0) {
                float q = -0.5 * (c1 + (c1 < 0.0 ? -1.0 : 1.0) * sqrt(disc));
                r[0] = q / c2;
                r[1] = q != 0.0 ? c0 / q : -1.0;
            }
        }
        for (int n = 0; n < 2; ++n) {
            float w = r[n];
            if (w < -tol || w > 1.0 + tol)
                continue;
            vec3 A = P.b[i] + w * P.n[i], E = e0 + w * e1, rr = ro - A;
            float b = dot(rd, E), c = dot(E, E), d = dot(rd, rr), e = dot(E, rr);
            float den = c - b * b; // |rd| = 1
            if (!(abs(den) > 1e-12 * c))
                continue; // the ray runs along the patch's line
            float t = (b * e - c * d) / den, sp = (e - b * d) / den;
            if (sp < -tol || sp > 1.0 + tol || !(t > t_from && t < best))
                continue;
            vec3 nn = cross(E, mix(P.n[i], P.n[j], sp));
            if (dot(nn, (A + sp * E) - (P.b[o] + w * P.n[o])) < 0.0)
                nn = -nn;
            if (!(dot(nn, rd) > 0.0))
                continue; // inwards: where the ray enters
            best = t;
            side = k;
        }
    }
    t_exit = best;
    return side;
}
#endif

void main()
{
#ifdef MESO_HULL_REJECT
    if (behind_hit()) {
        reject();
        return;
    }
#endif
    instance_begin();
    vec3 ro, rd;
    fragment_ray(ro, rd);
#if MESO_TECHNIQUE == 3
    Prism P = fetch_prism(v_prism);
    vec2 range = hull_levels(P);
    float tmin, tmax;
    int fmin, fmax;
    vec3 en;
    if (!hull_span(hull_prism(P, range), ro, rd, tmin, tmax, fmin, fmax, en)) {
        finish(false);
        return;
    }
    vec3 q0 = hull_point_to_texture(P, ro + tmin * rd, fmin, range);
    vec3 q1 = hull_point_to_texture(P, ro + tmax * rd, fmax, range);
#if MESO_PASS == MESO_PASS_FORWARD
    o_color = vec4(q0.z, q1.z, 0.5, 1.0); // a diagnostic: entry and exit w (no shading, no hook)
#elif MESO_PASS == MESO_PASS_GBUFFER
    // The hull face the depth lies on (fmax), facing the viewer.
    emit_obj(vec3(0.0), u_albedo, 1.0, facing(en, rd), ro + tmax * rd, rd);
#endif
    write_depth(ro + tmax * rd);
    finish(true);
#else
    // The walk (smooth shells, u_walk; runtime/rt_prism_walk.c): a ray that
    // leaves its prism through a side without a hit goes on in the prism
    // across that side, never back into the one it came from, for at most
    // 512 prisms (a grazing ray may cross many).
    int prism = v_prism, from = -1;
    float t_from = 0.0; // the walk: where the ray entered this prism, about
    for (int walked = 0; walked < 512; ++walked) {
        Prism P = fetch_prism(prism);
        vec3 hq;
        float hw;
        bool left;
        vec3 cq0, cq1;
        if (cast_prism(P, ro, rd, hq, hw, left, cq0, cq1)) {
            vec3 p = phi(P, hq);
#if MESO_PASS != MESO_PASS_DEPTH
            const bool curved = MESO_TECHNIQUE == 1;
            shade_hit(map_jacobian(P, curved ? vec3(hq.xy, hw) : hq, curved), vec3(tex_st(P, hq.xy), hw), p, rd);
#endif
            write_depth(p);
            finish(true);
            return;
        }
#if defined(MESO_HULL_REJECT) && MESO_TECHNIQUE == 0
        if (v_walk == 0 || !(left || g_no_span))
            break;
        float t_exit;
        int side = exit_side(P, ro, rd, t_from, t_exit);
        if (side < 0 && walked == 0 && g_no_span) {
            // rasterised on P's cap, the ray misses P: it enters the
            // neighbour across the edge the two caps share
            side = grazed_side(P, ro, rd);
            t_exit = t_from;
        } else if (side < 0 && !(t_exit < 1e30)) {
            side = chord_side(cq0, cq1); // no crossing found (rounding): the march's chord
            t_exit = t_from;
        }
        if (side < 0)
            break;
        int next = side_neighbour(prism, side);
        if (next < 0 || next == from)
            break;
        from = prism;
        prism = next;
        // the next prism's exit lies beyond this one (its entry here is
        // inwards for it); a little before, for rounding
        t_from = t_exit - 1e-5 * max(1.0, abs(t_exit));
#else
        break;
#endif
    }
    finish(false);
#endif
}
#endif
