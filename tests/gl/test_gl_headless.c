/* Headless OpenGL: an EGL surfaceless core context (4.x on llvmpipe) renders
 * a known pattern and a depth ramp into an FBO; the pixels read back are
 * compared with the pattern computed on the CPU. A GL test that cannot make a
 * context fails: it never skips. */
#include "test_util.h"

#include <GL/glcorearb.h>
#include <string.h>

#include "egl_context.h"

#define GLF(X)                                                                                              \
    X(PFNGLGETINTEGERVPROC, GetIntegerv) X(PFNGLGETSTRINGPROC, GetString) X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers) \
    X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer) X(PFNGLGENRENDERBUFFERSPROC, GenRenderbuffers)                     \
    X(PFNGLBINDRENDERBUFFERPROC, BindRenderbuffer) X(PFNGLRENDERBUFFERSTORAGEPROC, RenderbufferStorage)             \
    X(PFNGLFRAMEBUFFERRENDERBUFFERPROC, FramebufferRenderbuffer)                                                   \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus) X(PFNGLVIEWPORTPROC, Viewport)                        \
    X(PFNGLCLEARCOLORPROC, ClearColor) X(PFNGLCLEARPROC, Clear) X(PFNGLCREATESHADERPROC, CreateShader)             \
    X(PFNGLSHADERSOURCEPROC, ShaderSource) X(PFNGLCOMPILESHADERPROC, CompileShader)                                 \
    X(PFNGLGETSHADERIVPROC, GetShaderiv) X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                             \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram) X(PFNGLATTACHSHADERPROC, AttachShader)                                 \
    X(PFNGLLINKPROGRAMPROC, LinkProgram) X(PFNGLGETPROGRAMIVPROC, GetProgramiv) X(PFNGLUSEPROGRAMPROC, UseProgram)  \
    X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays) X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                       \
    X(PFNGLDRAWARRAYSPROC, DrawArrays) X(PFNGLREADPIXELSPROC, ReadPixels) X(PFNGLENABLEPROC, Enable)                \
    X(PFNGLDEPTHFUNCPROC, DepthFunc) X(PFNGLGETERRORPROC, GetError) X(PFNGLFINISHPROC, Finish)

static struct {
#define M(t, n) t n;
    GLF(M)
#undef M
} gl;

static void load(void)
{
#define L(t, n)                                          \
    {                                                    \
        void (*p)(void) = meso_egl_proc("gl" #n);        \
        assert(p && "GL entry point gl" #n);             \
        memcpy(&gl.n, &p, sizeof(p));                    \
    }
    GLF(L)
#undef L
}

static GLuint compile(GLenum type, const char* src)
{
    GLuint s = gl.CreateShader(type);
    gl.ShaderSource(s, 1, &src, NULL);
    gl.CompileShader(s);
    GLint ok = 0;
    gl.GetShaderiv(s, GL_COMPILE_STATUS, &ok);
    if (!ok) {
        char log[2048];
        gl.GetShaderInfoLog(s, sizeof(log), NULL, log);
        fprintf(stderr, "shader: %s\n", log);
    }
    assert(ok);
    return s;
}

enum { W = 64, H = 48, CELL = 8 };

static const char* vs =
    "#version 330 core\n"
    "void main() {\n"
    "  vec2 p = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));\n"
    "  gl_Position = vec4(p * 2.0 - 1.0, 0.0, 1.0);\n"
    "}\n";
/* Checkerboard of 8-pixel cells: red/blue, green = column index; depth ramp in x. */
static const char* fs =
    "#version 330 core\n"
    "out vec4 color;\n"
    "void main() {\n"
    "  ivec2 c = ivec2(gl_FragCoord.xy) / 8;\n"
    "  bool odd = ((c.x + c.y) & 1) == 1;\n"
    "  color = vec4(odd ? 1.0 : 0.0, float(c.x) / 255.0, odd ? 0.0 : 1.0, 1.0);\n"
    "  gl_FragDepth = (floor(gl_FragCoord.x) + 0.5) / 64.0;\n"
    "}\n";

static void renders_known_pattern(void)
{
    char why[256];
    meso_egl* e = meso_egl_create(why, sizeof(why));
    if (!e)
        fprintf(stderr, "EGL: %s\n", why);
    assert(e);
    load();
    GLint major = 0, minor = 0;
    gl.GetIntegerv(GL_MAJOR_VERSION, &major);
    gl.GetIntegerv(GL_MINOR_VERSION, &minor);
    fprintf(stderr, "  GL %d.%d on %s\n", major, minor, (const char*)gl.GetString(GL_RENDERER));
    assert(major >= 4); /* the issue asks for a 4.x core context; llvmpipe gives 4.5 */

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
    assert(gl.CheckFramebufferStatus(GL_FRAMEBUFFER) == GL_FRAMEBUFFER_COMPLETE);

    GLuint prog = gl.CreateProgram();
    gl.AttachShader(prog, compile(GL_VERTEX_SHADER, vs));
    gl.AttachShader(prog, compile(GL_FRAGMENT_SHADER, fs));
    gl.LinkProgram(prog);
    GLint ok = 0;
    gl.GetProgramiv(prog, GL_LINK_STATUS, &ok);
    assert(ok);
    GLuint vao;
    gl.GenVertexArrays(1, &vao);
    gl.BindVertexArray(vao);

    gl.Viewport(0, 0, W, H);
    gl.ClearColor(0, 0, 0, 0);
    gl.Clear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    gl.Enable(GL_DEPTH_TEST); /* gl_FragDepth reaches the buffer only with the test on */
    gl.DepthFunc(GL_ALWAYS);
    gl.UseProgram(prog);
    gl.DrawArrays(GL_TRIANGLES, 0, 3);
    gl.Finish();

    static uint8_t px[W * H * 4];
    static float depth[W * H];
    gl.ReadPixels(0, 0, W, H, GL_RGBA, GL_UNSIGNED_BYTE, px);
    gl.ReadPixels(0, 0, W, H, GL_DEPTH_COMPONENT, GL_FLOAT, depth);
    assert(gl.GetError() == GL_NO_ERROR);
    for (int y = 0; y < H; ++y)
        for (int x = 0; x < W; ++x) {
            const uint8_t* p = px + 4 * (y * W + x);
            int odd = ((x / CELL + y / CELL) & 1);
            assert(p[0] == (odd ? 255 : 0));
            assert(p[1] == x / CELL);
            assert(p[2] == (odd ? 0 : 255));
            assert(p[3] == 255);
            assert(fabsf(depth[y * W + x] - ((float)x + 0.5f) / 64.0f) < 1e-6f);
        }
    meso_egl_destroy(e);
}

int main(void)
{
    TEST_RUN(renders_known_pattern);
    return 0;
}
