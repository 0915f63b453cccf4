/*
 * rt_gl.h — the runtime's GL function table (internal).
 *
 * Every GL function the runtime calls is listed once in MESO_GL_FUNCS and
 * expanded into a table inside meso_rt (no statics, so several contexts can
 * coexist). MESO_GL_FUNCS holds what both OpenGL 3.3 core and OpenGL ES 3.2
 * have; what only one API (or version) has is in MESO_GL_FUNCS_OPTIONAL.
 * Types come from Khronos' glcorearb.h (the ES entry points used share its
 * prototypes and enum values), which declares no symbols unless
 * GL_GLEXT_PROTOTYPES is defined: the runtime links no GL library.
 */
#ifndef MESO_RT_GL_H
#define MESO_RT_GL_H

#include <GL/glcorearb.h>

/* X(type-suffix, name) → PFN<UPPER>PROC, member `name`. */
#define MESO_GL_FUNCS(X)                                                     \
    X(PFNGLGETSTRINGPROC, GetString)                                         \
    X(PFNGLGETSTRINGIPROC, GetStringi)                                       \
    X(PFNGLGETINTEGERVPROC, GetIntegerv)                                     \
    X(PFNGLGETERRORPROC, GetError)                                           \
    X(PFNGLENABLEPROC, Enable)                                               \
    X(PFNGLDISABLEPROC, Disable)                                             \
    X(PFNGLISENABLEDPROC, IsEnabled)                                         \
    X(PFNGLDEPTHFUNCPROC, DepthFunc)                                         \
    X(PFNGLDEPTHMASKPROC, DepthMask)                                         \
    X(PFNGLGENBUFFERSPROC, GenBuffers)                                       \
    X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                                 \
    X(PFNGLBINDBUFFERPROC, BindBuffer)                                       \
    X(PFNGLBUFFERDATAPROC, BufferData)                                       \
    X(PFNGLBUFFERSUBDATAPROC, BufferSubData)                                 \
    X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                             \
    X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)                       \
    X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                             \
    X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)                     \
    X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)             \
    X(PFNGLCREATESHADERPROC, CreateShader)                                   \
    X(PFNGLSHADERSOURCEPROC, ShaderSource)                                   \
    X(PFNGLCOMPILESHADERPROC, CompileShader)                                 \
    X(PFNGLGETSHADERIVPROC, GetShaderiv)                                     \
    X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                           \
    X(PFNGLDELETESHADERPROC, DeleteShader)                                   \
    X(PFNGLCREATEPROGRAMPROC, CreateProgram)                                 \
    X(PFNGLATTACHSHADERPROC, AttachShader)                                   \
    X(PFNGLLINKPROGRAMPROC, LinkProgram)                                     \
    X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                                   \
    X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)                         \
    X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                                 \
    X(PFNGLUSEPROGRAMPROC, UseProgram)                                       \
    X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)                       \
    X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)                           \
    X(PFNGLUNIFORMMATRIX3FVPROC, UniformMatrix3fv)                           \
    X(PFNGLUNIFORM3FVPROC, Uniform3fv)                                       \
    X(PFNGLUNIFORM1FPROC, Uniform1f)                                         \
    X(PFNGLDRAWELEMENTSPROC, DrawElements)                                   \
    X(PFNGLDRAWARRAYSPROC, DrawArrays)                                       \
    X(PFNGLUNIFORM1IPROC, Uniform1i)                                         \
    X(PFNGLUNIFORM4FVPROC, Uniform4fv)                                       \
    X(PFNGLUNIFORM2IVPROC, Uniform2iv)                                       \
    X(PFNGLUNIFORM3IPROC, Uniform3i)                                         \
    X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                                 \
    X(PFNGLBINDTEXTUREPROC, BindTexture)                                     \
    X(PFNGLGENTEXTURESPROC, GenTextures)                                     \
    X(PFNGLDELETETEXTURESPROC, DeleteTextures)                               \
    X(PFNGLTEXBUFFERPROC, TexBuffer)                                         \
    X(PFNGLTEXIMAGE2DPROC, TexImage2D)                                       \
    X(PFNGLTEXIMAGE3DPROC, TexImage3D)                                       \
    X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D)                                 \
    X(PFNGLTEXSUBIMAGE3DPROC, TexSubImage3D)                                 \
    X(PFNGLTEXPARAMETERIPROC, TexParameteri)                                 \
    X(PFNGLGENERATEMIPMAPPROC, GenerateMipmap)                               \
    X(PFNGLPIXELSTOREIPROC, PixelStorei)                                     \
    X(PFNGLCULLFACEPROC, CullFace)                                           \
    X(PFNGLFRONTFACEPROC, FrontFace)                                         \
    X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                               \
    X(PFNGLMAPBUFFERRANGEPROC, MapBufferRange)                               \
    X(PFNGLUNMAPBUFFERPROC, UnmapBuffer)                                     \
    X(PFNGLVIEWPORTPROC, Viewport)                                           \
    X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                             \
    X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)                       \
    X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                             \
    X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)                   \
    X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)               \
    X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                                     \
    X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv)                                 \
    X(PFNGLGETTEXLEVELPARAMETERIVPROC, GetTexLevelParameteriv)               \
    X(PFNGLGETBUFFERPARAMETERIVPROC, GetBufferParameteriv)                   \
    X(PFNGLGETINTEGERI_VPROC, GetIntegeri_v)                                 \
    X(PFNGLGETINTEGER64I_VPROC, GetInteger64i_v)                             \
    X(PFNGLBINDBUFFERRANGEPROC, BindBufferRange)                   \
    X(PFNGLDRAWARRAYSINSTANCEDPROC, DrawArraysInstanced)                     \
    X(PFNGLDRAWELEMENTSINSTANCEDPROC, DrawElementsInstanced)                   \
    X(PFNGLCOLORMASKPROC, ColorMask)                                         \
    X(PFNGLGETBOOLEANVPROC, GetBooleanv)                                     \
    X(PFNGLGETUNIFORMBLOCKINDEXPROC, GetUniformBlockIndex)                   \
    X(PFNGLUNIFORMBLOCKBINDINGPROC, UniformBlockBinding)

/* Entry points used only when the context has them (the stats counters of
 * OpenGL 4.3 / ES 3.1; glGetBufferSubData, which OpenGL ES lacks: ES maps
 * the buffer instead; the shells' hit image, rt_shell.c: OpenGL 4.4 or
 * ARB_clear_texture, ES with EXT_clear_texture under its EXT name); missing
 * ones are left NULL and never fail creation. */
#define MESO_GL_FUNCS_OPTIONAL(X)                         \
    X(PFNGLMEMORYBARRIERPROC, MemoryBarrier)            \
    X(PFNGLGETBUFFERSUBDATAPROC, GetBufferSubData)      \
    X(PFNGLBINDIMAGETEXTUREPROC, BindImageTexture)      \
    X(PFNGLTEXSTORAGE2DPROC, TexStorage2D)              \
    X(PFNGLCLEARTEXSUBIMAGEPROC, ClearTexSubImage)      \
    X(PFNGLCLEARTEXSUBIMAGEPROC, ClearTexSubImageEXT)

typedef struct mesoi_gl {
#define MESO_X_MEMBER(type, name) type name;
    MESO_GL_FUNCS(MESO_X_MEMBER)
    MESO_GL_FUNCS_OPTIONAL(MESO_X_MEMBER)
#undef MESO_X_MEMBER
} mesoi_gl;

#endif /* MESO_RT_GL_H */
