// frusta_common.glsl - shared by the frusta vertex and fragment shaders.
// The runtime prepends "#version", MESO_FRUSTA_TEXELS (texels per
// primitive), MESO_FRUSTA_CORNER0 (its first corner texel) and, on OpenGL
// 4.3+ with counters, MESO_STATS. runtime/rt_frusta.c documents the
// texel layout.

uniform samplerBuffer u_prims; // MESO_FRUSTA_TEXELS RGBA32F texels per primitive
// u_mvp, u_inv_mvp: instance.glsl
