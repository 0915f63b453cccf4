// instance.glsl - how an object's matrices reach the shaders, for one draw
// or for many instances in one instanced draw (runtime/rt_instances.c).
// Prepended after "#version" (and, in vertex shaders, after
// "#define MESO_STAGE_VERTEX 1") to the sources of every kind.
//
// One object, one draw (meso_rt_draw): u_instanced is 0 and the per-object
// values come from the uniforms below, as the runtime sets them.
// Instanced (meso_rt_draw_instanced, meso_rt_draw_list): u_instanced is 1
// and each instance's values come from the texture buffer u_instances,
// MESO_INSTANCE_TEXELS RGBA32F texels per instance, fetched once per vertex
// (index gl_InstanceID) and once per fragment (the flat varying
// v_instance). Layout (rt_instances.c writes it):
//   0-3  object -> clip (columns)      4-7  clip -> object (columns)
//   8    light_obj.xyz, err_scale      9    prim_base, -, -, -
//   10-13 model (object -> world columns)
// Vertex stages fetch 0-3 and 9, fragment stages 0-8; 10-13 where the
// runtime defines MESO_INSTANCE_MODEL (meshes, cells) and in fragment
// stages of the depth-free passes that need world space (G-buffer, hook).
// The same shader code serves both: main() calls instance_begin() first,
// and after it the names u_mvp, u_inv_mvp, u_light_obj, u_err_scale,
// u_env_rot and u_model stand for the selected values (macros below), so
// the kinds' code reads them as before. With MESO_SINGLE (the slice
// renderer, never instanced) the uniforms are used as they are.

uniform mat4 u_mvp;         // object -> clip
uniform mat4 u_inv_mvp;     // clip -> object
uniform vec3 u_light_obj;   // towards the light, object space, unit
uniform float u_err_scale;  // shells: error_px * object units per pixel per unit w_clip
uniform mat3 u_env_rot;     // cells: object -> world directions
uniform mat4 u_model;       // mesh: object -> world

#ifdef MESO_SINGLE
void instance_begin()
{
}
#else
#define MESO_INSTANCE_TEXELS 14
uniform int u_instanced;            // 1: the values below come from u_instances
uniform int u_instance_base;        // added to gl_InstanceID (animated shells draw one call per frame)
uniform samplerBuffer u_instances;  // MESO_INSTANCE_TEXELS texels per instance
#ifdef MESO_STAGE_VERTEX
flat out int v_instance;
#else
flat in int v_instance;
#endif

mat4 g_mvp;
mat4 g_inv_mvp;
vec3 g_light_obj;
float g_err_scale;
mat3 g_env_rot;
mat4 g_model;
int g_prim_base; // frusta: the first primitive of the instance's pose slot

mat4 instance_mat4(int base)
{
    return mat4(texelFetch(u_instances, base), texelFetch(u_instances, base + 1), texelFetch(u_instances, base + 2),
                texelFetch(u_instances, base + 3));
}

void instance_begin()
{
#ifdef MESO_STAGE_VERTEX
    int i = gl_InstanceID + u_instance_base;
    v_instance = i;
#else
    int i = v_instance;
#endif
    if (u_instanced == 0) {
        g_mvp = u_mvp;
        g_inv_mvp = u_inv_mvp;
        g_light_obj = u_light_obj;
        g_err_scale = u_err_scale;
        g_env_rot = u_env_rot;
        g_model = u_model;
        g_prim_base = 0;
        return;
    }
    // Each stage fetches what it reads (llvmpipe shades vertices on the
    // draw call's thread: fetches per vertex are CPU time).
    int b = MESO_INSTANCE_TEXELS * i;
    g_mvp = instance_mat4(b);
#ifdef MESO_STAGE_VERTEX
    g_prim_base = int(texelFetch(u_instances, b + 9).x);
#else
    g_inv_mvp = instance_mat4(b + 4);
    vec4 t8 = texelFetch(u_instances, b + 8);
    g_light_obj = t8.xyz;
    g_err_scale = t8.w;
#endif
#if defined(MESO_INSTANCE_MODEL) || (!defined(MESO_STAGE_VERTEX) && (MESO_PASS != 0 || defined(MESO_HOOK)))
    // Meshes and cells always; every kind's fragments where pass_out.glsl
    // turns normals and points to world space (G-buffer, shading hook).
    g_model = instance_mat4(b + 10);
    g_env_rot = mat3(g_model) / length(g_model[0].xyz);
#endif
}

#define u_mvp g_mvp
#define u_inv_mvp g_inv_mvp
#define u_light_obj g_light_obj
#define u_err_scale g_err_scale
#define u_env_rot g_env_rot
#define u_model g_model
#endif
