// shell_slices_frag.glsl - slice-based direct isosurface rendering of shells
// (MESO_SHELL_SLICES), papers/volume-textures-lp-averaged-shells.md sec. 5,
// "Slice-based direct isosurface rendering" and "Algorithm details",
// Figures 11-13. Slice geometry: shell_slices_vert.glsl; passes: rt_slices.c.
//
// alpha. The paper's isosurface is alpha = 1/2 of a density; a shell's
// texture function is a height field or a density (FORMAT.md sec. 7.2), so
// here alpha - 1/2 = a(s,t',w) with a = h(s,t') - w for height fields and
// a = density - 1/2 for volumes: a >= 0 exactly where the ray casters call
// the texture solid, and a is continuous, so it can be interpolated.
// The normal is the texture's gradient (tex_gradient) taken through the
// prism's Jacobian at the point (jacobian_normal; the paper interpolates the
// Jacobian from the vertices, here it is computed exactly per fragment).
//
// SLICE_PASS
//  0  no interpolation: the alpha test (discard a < 0) and the depth test
//     keep the first slice inside; shaded with the normal there, depth of
//     the slice point (into the host's framebuffer directly).
//  1  first pass of the two-pass variants, into the offscreen target:
//     the same fragments as 0, writing T1 = (s, t', w, a1) and, as a
//     fallback for pixels pass 2 leaves empty, pass 0's colour and depth.
//  2  second pass, normal interpolation; 3  second pass, texture-coordinate
//     interpolation (the paper's). Fragments with a >= 0 (inside) or not in
//     front of Z1 are discarded; the reversed depth test (GREATER) keeps
//     the last slice outside before the first inside one, t2, a2. The
//     crossing is at f = -a2 / (a1 - a2) of the way from t2 to t1 - the
//     paper's t3 = ((a1 - 1/2) t2 - (a2 - 1/2) t1) / (a1 - a2), checked:
//     t3 = t1 when a1 = 1/2, t3 = t2 when a2 = 1/2. 3 looks the gradient up
//     at t3; 2 mixes the normals looked up at t2 and t1 with the same f.
//     Both also place the hit at p3 = mix(p2, p1, f): p1 and p2 lie on the
//     same pixel's view ray, so p3 is on it too, and its depth is written
//     (the paper leaves a slice fragment's own depth).
//  4  composite: the second pass's colour and depth where it found a slice
//     outside, else the first pass's, into the host's framebuffer with its
//     depth test.
// The paper renders extra slices in front and behind when the first or last
// slice is inside. Here a pixel whose first inside fragment has no slice
// outside in front of it (solid reaching the top level, or entered through
// a side wall with nothing outside before it) keeps pass 1's colour and
// depth: no interpolation, never a hole. Extra slices are not rendered,
// decided: a shell's texture function is defined on the shell only (a
// volume clamps in w, a height field's a = h - w never crosses between the
// cap and a level above it), so a slice beyond a cap cannot bracket a
// crossing; where solid reaches a face, the surface is the face itself -
// the exact reference's ray meets the solid at the prism's boundary there
// (runtime/reference/shell_reference.c, march_prism), which is the first
// slice inside, drawn as pass 1 draws it.
// Texture coordinates from different charts cannot be interpolated (a uv
// seam between the two slices' prisms, or prisms without uvs, each its own
// chart). The test: t1 read in the chart of t2's prism (prism_coords, then
// Phi) must land within a quarter of |p1 - p2| of p1; else the pixel keeps
// t1 and p1 (no interpolation). Within one chart it lands on p1 exactly
// (same prism, or a flat neighbour) or nearly (a curved neighbour: the
// error is second order in the distance). The paper instead renders texture
// boundaries twice, offset towards each texture.

flat in int v_prism;
in vec3 v_q;
in vec3 v_stw;
in vec3 v_pos;

#if SLICE_PASS == 1
layout(location = 0) out vec4 o_tex;   // (s, t', w, a)
layout(location = 1) out vec4 o_color; // colour, window depth
#elif SLICE_PASS != 0
out vec4 o_color;
#endif
// SLICE_PASS 0 writes through pass_out.glsl (emit), in every meso_rt_pass.

uniform sampler2D u_first;  // pass 2/3: T1; pass 4: the first pass's colour and depth
uniform sampler2D u_second; // pass 2/3: Z1 (depth); pass 4: the second pass's colour and depth

float slice_alpha(vec3 stw)
{
    if (u_tex_kind == 1)
        return textureLod(u_height, stw.xy, 0.0).r - stw.z;
    if (u_tex_kind == 2)
        return textureLod(u_volume, stw, 0.0).r - 0.5;
    return 1.0;
}

// The texture's shading at stw (shell_texfn.glsl shading_at: normal,
// albedo, w at the footprint's level) for the prism P at q = (u, v, w),
// object point p: its smooth mapping Phi is bilinear, so the Jacobian at q
// is exact.
Shading slice_shading(Prism P, vec3 q, vec3 stw, vec3 p, vec3 rd)
{
    float t = 1.0 - q.x - q.y;
    vec3 ju = (P.b[1] - P.b[0]) + q.z * (P.n[1] - P.n[0]);
    vec3 jv = (P.b[2] - P.b[0]) + q.z * (P.n[2] - P.n[0]);
    vec3 jw = t * P.n[0] + q.x * P.n[1] + q.y * P.n[2];
    Shading h = shading_at(tex_jacobian(P, ju, jv, jw), stw, p, rd);
    h.n = normalize(h.n);
    return h;
}

// (u, v, w) in P of texture coordinates stw (the inverse of tex_st).
vec3 prism_coords(Prism P, vec3 stw)
{
    vec2 e1 = P.uv[1] - P.uv[0], e2 = P.uv[2] - P.uv[0], d = stw.xy - P.uv[0];
    float det = e1.x * e2.y - e2.x * e1.y;
    return vec3((d.x * e2.y - e2.x * d.y) / det, (e1.x * d.y - d.x * e1.y) / det, stw.z);
}

void main()
{
#if SLICE_PASS == 4
    ivec2 pix = ivec2(gl_FragCoord.xy) - ivec2(u_viewport.xy);
    vec4 c = texelFetch(u_second, pix, 0);
    if (c.a > 1.5) // cleared: nothing drawn (depths are 0..1)
        c = texelFetch(u_first, pix, 0);
    if (c.a > 1.5)
        discard;
    o_color = vec4(c.rgb, 1.0);
    gl_FragDepth = c.a;
#else
    vec3 ro, rd;
    fragment_ray(ro, rd);
    Prism P = fetch_prism(v_prism);
    float a = slice_alpha(v_stw);
#if SLICE_PASS <= 1
    if (a < 0.0)
        discard;
#if SLICE_PASS == 0
#if MESO_PASS != MESO_PASS_DEPTH
    Shading h = slice_shading(P, v_q, v_stw, v_pos, rd);
    emit_obj(h.color, h.albedo, occlusion(h.w), facing(h.n, rd), v_pos, rd);
#endif
#else
    vec3 col = slice_shading(P, v_q, v_stw, v_pos, rd).color;
    o_tex = vec4(v_stw, a);
    o_color = vec4(col, gl_FragCoord.z);
#endif
#else
    ivec2 pix = ivec2(gl_FragCoord.xy);
    float z1 = texelFetch(u_second, pix, 0).r;
    float far_clear = u_depth_ndc.x > u_depth_ndc.z ? 0.0 : 1.0; // rt_slices.c clears Z1 to it
    if (a >= 0.0 || z1 == far_clear || !nearer(gl_FragCoord.z, z1))
        discard;
    vec4 T1 = texelFetch(u_first, pix, 0);
    // p1: the first inside slice's point, on this pixel's ray at depth z1.
    vec3 p1 = unproject(gl_FragCoord.xy, window_to_ndc(z1));
    float f = -a / (T1.w - a);
    if (length(phi(P, prism_coords(P, T1.xyz)) - p1) > 0.25 * length(p1 - v_pos))
        f = 1.0; // another chart
    vec3 t3 = mix(v_stw, T1.xyz, f);
    vec3 p3 = mix(v_pos, p1, f);
    Shading h = slice_shading(P, prism_coords(P, t3), t3, p3, rd);
#if SLICE_PASS == 2
    // Normal interpolation: the two slices' normals mixed, shaded once.
    h.n = mix(slice_shading(P, v_q, v_stw, p3, rd).n, slice_shading(P, prism_coords(P, T1.xyz), T1.xyz, p3, rd).n, f);
    h.color = shade(h.albedo, h.n, h.w, rd);
#endif
    o_color = vec4(h.color, window_depth(p3));
#endif
#endif
}
