// The one table of OpenGL entry points the GL layer calls. It is filled at run time from a
// caller-given loader (OSMesaGetProcAddress for the headless worker; glfwGetProcAddress for a
// windowed client), because core-profile entry points past GL 1.x are not exported by libGL /
// libOSMesa and libepoxy aborts under OSMesa. Only the functions listed below are loaded.
#ifndef PDSM_GL_GL_FUNCTIONS_H_
#define PDSM_GL_GL_FUNCTIONS_H_

#include <GL/glcorearb.h>

#include "absl/status/statusor.h"

namespace pdsm::gl {

// Same signature as OSMesaGetProcAddress and glfwGetProcAddress.
using GlProc = void (*)();
using GetProcAddressFn = GlProc (*)(const char* name);

// X(PFN type, member name): the member is called as gl.Name(...), loaded from "glName".
#define PDSM_GL_FUNCTION_LIST(X)                                 \
  X(PFNGLGETERRORPROC, GetError)                                 \
  X(PFNGLGETINTEGERVPROC, GetIntegerv)                           \
  X(PFNGLGETSTRINGPROC, GetString)                               \
  X(PFNGLENABLEPROC, Enable)                                     \
  X(PFNGLDISABLEPROC, Disable)                                   \
  X(PFNGLVIEWPORTPROC, Viewport)                                 \
  X(PFNGLSCISSORPROC, Scissor)                                   \
  X(PFNGLDEPTHFUNCPROC, DepthFunc)                               \
  X(PFNGLDEPTHMASKPROC, DepthMask)                               \
  X(PFNGLPOLYGONOFFSETPROC, PolygonOffset)                       \
  X(PFNGLCLIPCONTROLPROC, ClipControl)                           \
  X(PFNGLCLEARBUFFERFVPROC, ClearBufferfv)                       \
  X(PFNGLPIXELSTOREIPROC, PixelStorei)                           \
  X(PFNGLREADBUFFERPROC, ReadBuffer)                             \
  X(PFNGLREADPIXELSPROC, ReadPixels)                             \
  X(PFNGLDRAWBUFFERSPROC, DrawBuffers)                           \
  X(PFNGLDRAWELEMENTSPROC, DrawElements)                         \
  X(PFNGLMULTIDRAWELEMENTSPROC, MultiDrawElements)               \
  X(PFNGLGENBUFFERSPROC, GenBuffers)                             \
  X(PFNGLDELETEBUFFERSPROC, DeleteBuffers)                       \
  X(PFNGLBINDBUFFERPROC, BindBuffer)                             \
  X(PFNGLBUFFERDATAPROC, BufferData)                             \
  X(PFNGLBUFFERSUBDATAPROC, BufferSubData)                       \
  X(PFNGLCOPYBUFFERSUBDATAPROC, CopyBufferSubData)               \
  X(PFNGLGETBUFFERSUBDATAPROC, GetBufferSubData)                 \
  X(PFNGLGENVERTEXARRAYSPROC, GenVertexArrays)                   \
  X(PFNGLDELETEVERTEXARRAYSPROC, DeleteVertexArrays)             \
  X(PFNGLBINDVERTEXARRAYPROC, BindVertexArray)                   \
  X(PFNGLENABLEVERTEXATTRIBARRAYPROC, EnableVertexAttribArray)   \
  X(PFNGLDISABLEVERTEXATTRIBARRAYPROC, DisableVertexAttribArray) \
  X(PFNGLVERTEXATTRIBPOINTERPROC, VertexAttribPointer)           \
  X(PFNGLGENTEXTURESPROC, GenTextures)                           \
  X(PFNGLDELETETEXTURESPROC, DeleteTextures)                     \
  X(PFNGLBINDTEXTUREPROC, BindTexture)                           \
  X(PFNGLTEXIMAGE2DPROC, TexImage2D)                             \
  X(PFNGLTEXPARAMETERIPROC, TexParameteri)                       \
  X(PFNGLGENFRAMEBUFFERSPROC, GenFramebuffers)                   \
  X(PFNGLDELETEFRAMEBUFFERSPROC, DeleteFramebuffers)             \
  X(PFNGLBINDFRAMEBUFFERPROC, BindFramebuffer)                   \
  X(PFNGLFRAMEBUFFERTEXTURE2DPROC, FramebufferTexture2D)         \
  X(PFNGLCHECKFRAMEBUFFERSTATUSPROC, CheckFramebufferStatus)     \
  X(PFNGLCREATESHADERPROC, CreateShader)                         \
  X(PFNGLDELETESHADERPROC, DeleteShader)                         \
  X(PFNGLSHADERSOURCEPROC, ShaderSource)                         \
  X(PFNGLCOMPILESHADERPROC, CompileShader)                       \
  X(PFNGLGETSHADERIVPROC, GetShaderiv)                           \
  X(PFNGLGETSHADERINFOLOGPROC, GetShaderInfoLog)                 \
  X(PFNGLCREATEPROGRAMPROC, CreateProgram)                       \
  X(PFNGLDELETEPROGRAMPROC, DeleteProgram)                       \
  X(PFNGLATTACHSHADERPROC, AttachShader)                         \
  X(PFNGLDETACHSHADERPROC, DetachShader)                         \
  X(PFNGLLINKPROGRAMPROC, LinkProgram)                           \
  X(PFNGLGETPROGRAMIVPROC, GetProgramiv)                         \
  X(PFNGLGETPROGRAMINFOLOGPROC, GetProgramInfoLog)               \
  X(PFNGLUSEPROGRAMPROC, UseProgram)                             \
  X(PFNGLGETUNIFORMLOCATIONPROC, GetUniformLocation)             \
  X(PFNGLUNIFORM1FPROC, Uniform1f)                               \
  X(PFNGLUNIFORM1IPROC, Uniform1i)                               \
  X(PFNGLUNIFORMMATRIX4FVPROC, UniformMatrix4fv)                 \
  /* Used by the viewer (client/view): */                        \
  X(PFNGLUNIFORM2FPROC, Uniform2f)                               \
  X(PFNGLUNIFORM3FPROC, Uniform3f)                               \
  X(PFNGLUNIFORM2IPROC, Uniform2i)                               \
  X(PFNGLUNIFORMMATRIX3FVPROC, UniformMatrix3fv)                 \
  X(PFNGLACTIVETEXTUREPROC, ActiveTexture)                       \
  X(PFNGLBINDBUFFERBASEPROC, BindBufferBase)                     \
  X(PFNGLTEXIMAGE3DPROC, TexImage3D)                             \
  X(PFNGLTEXSUBIMAGE2DPROC, TexSubImage2D)                       \
  X(PFNGLFRAMEBUFFERTEXTURELAYERPROC, FramebufferTextureLayer)   \
  X(PFNGLBLITFRAMEBUFFERPROC, BlitFramebuffer)                   \
  X(PFNGLDRAWARRAYSPROC, DrawArrays)                             \
  X(PFNGLFINISHPROC, Finish)                                     \
  X(PFNGLFLUSHPROC, Flush)

// Plain table of function pointers; copyable, and valid only while a context made by the same
// driver is current (GL entry points dispatch on the current context). Thread-compatible.
struct GlFunctions {
#define PDSM_GL_DECLARE_MEMBER(type, name) type name = nullptr;
  PDSM_GL_FUNCTION_LIST(PDSM_GL_DECLARE_MEMBER)
#undef PDSM_GL_DECLARE_MEMBER

  // Fills every entry through `get_proc_address`. Returns NOT_FOUND naming the first entry
  // point the loader did not return. Note that some loaders (Mesa's) hand out dispatch stubs
  // for any "gl*" name, so a GL version check is still the caller's job.
  static absl::StatusOr<GlFunctions> Load(GetProcAddressFn get_proc_address);
};

}  // namespace pdsm::gl

#endif  // PDSM_GL_GL_FUNCTIONS_H_
