/* libmeso MESH objects on llvmpipe: a baked unit sphere is streamed from a
 * .meso image in memory, uploaded and drawn; coverage and depth read back
 * from the FBO are compared with an analytic ray cast of the unit sphere.
 * Twice: tests/data/sphere.obj, which goes up with 16-bit indices, and a
 * generated UV sphere of 80,601 vertices, past 65535, which goes up with
 * 32-bit ones (meso_rt.h, memory_budget).
 * Also: GL state is restored, handles are checked, Draco without a decoder
 * is refused cleanly. */
#include "test_util.h"

#include <GL/glcorearb.h>
#include <string.h>

#include "adapters.h"
#include "camera.h"
#include "egl_context.h"
#include "gl_api.h"
#include "mesh_chunk.h"
#include "meso_layout.h"
#include "meso_rt.h"

#define GLF(X)                                                                                                   \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                      \
    X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers) X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer)                  \
    X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage) X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer) \
    X(PFNGLVIEWPORTPROC, Viewport) X(PFNGLCLEARCOLORPROC, ClearColor) X(PFNGLCLEARPROC, Clear)                     \
    X(PFNGLREADPIXELSPROC, ReadPixels) X(PFNGLGETINTEGERVPROC, GetIntegerv) X(PFNGLISENABLEDPROC, IsEnabled)       \
    X(PFNGLDEPTHFUNCPROC, DepthFunc) X(PFNGLDISABLEPROC, Disable) X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv)

static struct {
#define M(t, n) t n;
    GLF(M)
#undef M
} gl;

enum { W = 128, H = 96 };
static const double EYE_Z = 3.0, FOVY = 50.0 * M_PI / 180.0, ZNEAR = 0.5, ZFAR = 10.0;

/* Analytic: the eye ray through the pixel centre, its closest distance to the
 * origin, and (when it hits the unit sphere) the eye-space depth of the hit. */
static double ray_sphere(int x, int y, double radius, double* hit_depth)
{
    const double t = tan(FOVY / 2), aspect = (double)W / H;
    double dx = (2.0 * (x + 0.5) / W - 1.0) * t * aspect, dy = (2.0 * (y + 0.5) / H - 1.0) * t, dz = -1.0;
    double len = sqrt(dx * dx + dy * dy + dz * dz);
    dx /= len, dy /= len, dz /= len;
    const double o[3] = {0, 0, EYE_Z};
    double b = o[0] * dx + o[1] * dy + o[2] * dz;
    double c2 = o[0] * o[0] + o[1] * o[1] + o[2] * o[2] - b * b; /* squared distance ray-origin */
    double dist = sqrt(c2 > 0 ? c2 : 0);
    *hit_depth = -1;
    if (dist < radius) {
        double s = -b - sqrt(radius * radius - c2);
        *hit_depth = -(s * dz); /* eye-space distance along -z */
    }
    return dist;
}

/* Smallest distance from the origin to a face plane of the mesh: the
 * polyhedron lies between the spheres of this radius and radius 1. */
static double inner_radius;

/* A UV sphere of radius 1, its normals the positions: (RINGS + 1) x
 * (AROUND + 1) vertices (the seam and the poles repeated). */
enum { AROUND = 400, RINGS = 200 };
static void uv_sphere(meso_mesh* m)
{
    const uint32_t nv = (RINGS + 1) * (AROUND + 1), nt = 2 * RINGS * AROUND;
    *m = (meso_mesh){.vertex_count = nv, .triangle_count = nt, .positions = malloc(12 * (size_t)nv),
                     .normals = malloc(12 * (size_t)nv), .indices = malloc(12 * (size_t)nt)};
    assert(m->positions && m->normals && m->indices);
    for (uint32_t r = 0; r <= RINGS; ++r)
        for (uint32_t a = 0; a <= AROUND; ++a) {
            const double th = M_PI * r / RINGS, ph = 2 * M_PI * a / AROUND;
            const float p[3] = {(float)(sin(th) * cos(ph)), (float)cos(th), (float)(sin(th) * sin(ph))};
            memcpy(m->positions + 3 * (r * (AROUND + 1) + a), p, sizeof p);
            memcpy(m->normals + 3 * (r * (AROUND + 1) + a), p, sizeof p);
        }
    uint32_t* t = m->indices;
    for (uint32_t r = 0; r < RINGS; ++r)
        for (uint32_t a = 0; a < AROUND; ++a) {
            const uint32_t v = r * (AROUND + 1) + a, w = v + AROUND + 1;
            const uint32_t quad[6] = {v, v + 1, w, v + 1, w + 1, w}; /* counter-clockwise from outside */
            memcpy(t, quad, sizeof quad);
            t += 6;
        }
}

static uint8_t* bake_sphere(size_t* size, int draco, int generated)
{
    meso_mesh m;
    meso_error err = {0};
    if (generated)
        uv_sphere(&m);
    else
        assert(meso_openmesh_read(test_data("sphere.obj"), &m, NULL, &err) == MESO_OK);
    inner_radius = 1.0;
    for (uint32_t t = 0; t < m.triangle_count; ++t) {
        const float* a = m.positions + 3 * m.indices[3 * t];
        const float* b = m.positions + 3 * m.indices[3 * t + 1];
        const float* c = m.positions + 3 * m.indices[3 * t + 2];
        double e1[3], e2[3], n[3];
        for (int k = 0; k < 3; ++k) {
            e1[k] = (double)b[k] - a[k];
            e2[k] = (double)c[k] - a[k];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        const double len = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (len > 0.0) /* the UV sphere's poles have degenerate triangles */
            inner_radius = fmin(inner_radius, fabs(n[0] * a[0] + n[1] * a[1] + n[2] * a[2]) / len);
    }
    meso_mesh_chunk ch;
    meso_draco_options o = {14, 10, 12, 7};
    assert(meso_bake_mesh_chunk(&m, draco ? &o : NULL, &ch, &err) == MESO_OK);
    meso_object_record rec = {.id = 7, .kind = MESO_OBJECT_MESH, .bbox_min = {-1, -1, -1}, .bbox_max = {1, 1, 1}};
    snprintf(rec.name, sizeof(rec.name), "sphere");
    uint8_t objt[MESO_OBJT_RECORD_SIZE];
    meso_object_record_encode(&rec, objt);
    meso_writer* w;
    assert(meso_writer_create(NULL, &w) == MESO_OK);
    assert(meso_writer_add(w, &(meso_chunk_desc){.type = MESO_CHUNK_OBJT}, objt, sizeof(objt), &err) == MESO_OK);
    assert(meso_writer_add(w,
                           &(meso_chunk_desc){.type = MESO_CHUNK_MESH, .object = 7, .encoding = ch.encoding,
                                              .decoded_size = ch.decoded_size},
                           ch.data, ch.size, &err) == MESO_OK);
    assert(meso_writer_finish(w, NULL, 0, size) == MESO_OK);
    uint8_t* buf = malloc(*size);
    assert(meso_writer_finish(w, buf, *size, size) == MESO_OK);
    meso_writer_destroy(w);
    free(ch.data);
    meso_mesh_free(&m);
    return buf;
}

static void setup_fbo(void)
{
    GLuint fbo, rb[2];
    gl.GenFramebuffers(1, &fbo);
    gl.BindFramebuffer(GL_FRAMEBUFFER, fbo);
    gl.GenRenderbuffers(2, rb);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[0]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_RGBA8, W, H);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_RENDERBUFFER, rb[0]);
    gl.BindRenderbuffer(GL_RENDERBUFFER, rb[1]);
    gl.RenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, W, H);
    gl.FramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, rb[1]);
    gl.Viewport(0, 0, W, H);
}

static void sphere_matches_analytic_coverage_and_depth(meso_rt* rt, int generated)
{
    size_t size;
    uint8_t* img = bake_sphere(&size, 0, generated);
    meso_file* f;
    meso_error err;
    assert(meso_file_open_memory(img, size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    assert(meso_rt_load_object(rt, f, 7, &obj) == MESO_OK);
    meso_file_close(f);
    free(img);

    float lo[3], hi[3];
    assert(meso_rt_object_bounds(rt, obj, lo, hi) == MESO_OK);
    assert(lo[0] == -1.0f && hi[2] == 1.0f);

    static const float far = 1.0f;
    gl.ClearColor(0, 0, 0, 0);
    gl.Clear(GL_COLOR_BUFFER_BIT);
    gl.ClearBufferfv(GL_DEPTH, 0, &far); /* glClearDepth is desktop only */
    gl.Disable(GL_DEPTH_TEST);
    gl.DepthFunc(GL_GEQUAL); /* host state that draw must restore */
    meso_rt_draw_desc d = {.depth_func = GL_LESS}; /* the draw's own; GL_GEQUAL comes back after */
    const double eye[3] = {0, 0, EYE_Z}, at[3] = {0, 0, 0}, up[3] = {0, 1, 0};
    meso_camera_look_at(d.view, eye, at, up); /* looking down -z */
    meso_camera_perspective(d.proj, FOVY, (double)W / H, ZNEAR, ZFAR);
    assert(meso_rt_draw(rt, obj, &d) == MESO_OK);
    GLint func = 0;
    gl.GetIntegerv(GL_DEPTH_FUNC, &func);
    assert(func == GL_GEQUAL);
    assert(!gl.IsEnabled(GL_DEPTH_TEST));

    static uint8_t px[W * H * 4];
    static float depth[W * H];
    gl.ReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, px);
    gl.ReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    int inside = 0, outside = 0, depth_checked = 0;
    double worst_depth = 0;
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            double hit, hit_inner;
            const double dist = ray_sphere(x, y, 1.0, &hit);
            ray_sphere(x, y, inner_radius, &hit_inner);
            const int covered = px[4 * (y * W + x) + 3] != 0;
            if (dist < inner_radius) { /* inside the polyhedron's silhouette */
                assert(covered);
                ++inside;
            } else if (dist > 1.0) { /* misses the circumscribing sphere */
                assert(!covered);
                assert(depth[y * W + x] == 1.0f);
                ++outside;
            }
            if (dist < inner_radius - 0.01) {
                /* Window depth back to eye-space distance. */
                const double zn = 2.0 * depth[y * W + x] - 1.0;
                const double ze = 2.0 * ZNEAR * ZFAR / (ZFAR + ZNEAR - zn * (ZFAR - ZNEAR));
                /* The surface hit lies between the hits of the two spheres
                 * (1e-4: float depth and rasterisation). */
                worst_depth = fmax(worst_depth, fabs(ze - hit));
                assert(ze >= hit - 1e-4 && ze <= hit_inner + 1e-4);
                ++depth_checked;
            }
        }
    fprintf(stderr, "  %s: inner radius %.5f; covered %d, background %d, depth checked %d (worst %.5f)\n",
            generated ? "UV sphere, 80601 vertices" : "sphere.obj", inner_radius, inside, outside, depth_checked,
            worst_depth);
    assert(inside > 1000 && outside > 1000);
    meso_rt_release_object(rt, obj);
    assert(meso_rt_draw(rt, obj, &d) == MESO_ERR_INVALID_ARG); /* stale handle */
    meso_rt_object again;
    /* The reused slot must get a new id, so the old handle stays stale. */
    img = bake_sphere(&size, 0, generated);
    assert(meso_file_open_memory(img, size, NULL, &f, &err) == MESO_OK);
    assert(meso_rt_load_object(rt, f, 7, &again) == MESO_OK);
    assert(again.id != obj.id);
    assert(meso_rt_draw(rt, obj, &d) == MESO_ERR_INVALID_ARG);
    assert(meso_rt_load_object(rt, f, 8, &obj) == MESO_ERR_NOT_FOUND && obj.id == 0);
    meso_file_close(f);
    free(img);
    meso_rt_release_object(rt, again);
}

static void draco_needs_a_decoder(meso_rt* rt)
{
    size_t size;
    uint8_t* img = bake_sphere(&size, 1, 0);
    meso_file* f;
    meso_error err;
    assert(meso_file_open_memory(img, size, NULL, &f, &err) == MESO_OK);
    meso_rt_object obj;
    assert(meso_rt_load_object(rt, f, 7, &obj) == MESO_ERR_UNSUPPORTED);
    assert(obj.id == 0);
    meso_file_close(f);
    /* With the host's decoder (here the baker's Draco adapter) it loads. */
    meso_decoder dec = meso_bake_draco_decoder();
    assert(meso_file_open_memory(img, size, &(meso_open_desc){.decoders = &dec, .decoder_count = 1}, &f, &err) ==
           MESO_OK);
    assert(meso_rt_load_object(rt, f, 7, &obj) == MESO_OK);
    meso_rt_release_object(rt, obj);
    meso_file_close(f);
    free(img);
}

int main(void)
{
    char why[256];
    meso_egl* e = test_egl_create(why, sizeof(why));
    if (!e)
        fprintf(stderr, "EGL: %s\n", why);
    assert(e);
#define L(t, n)                                   \
    {                                             \
        void (*p)(void) = meso_egl_proc("gl" #n); \
        assert(p);                                \
        memcpy(&gl.n, &p, sizeof(p));             \
    }
    GLF(L)
#undef L
    setup_fbo();
    meso_rt* rt;
    assert(meso_rt_create(&(meso_rt_desc){.gl_get_proc_address = meso_egl_proc}, &rt) == MESO_OK);
    assert(meso_rt_gl_is_es(rt) == (test_gl_api() == MESO_EGL_GLES)); /* the API asked for */
    sphere_matches_analytic_coverage_and_depth(rt, 0);
    sphere_matches_analytic_coverage_and_depth(rt, 1);
    draco_needs_a_decoder(rt);
    meso_rt_destroy(rt);
    meso_egl_destroy(e);
    return 0;
}
