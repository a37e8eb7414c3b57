// Move-only RAII owners of GL object names (buffers, vertex arrays, textures, framebuffers,
// shaders, programs). Each keeps a pointer to the function table it was made with; the table
// and the context that made the object must outlive it, and that context must be current when
// it is destroyed (the owner of the context arranges both).
#ifndef PDSM_GL_GL_OBJECTS_H_
#define PDSM_GL_GL_OBJECTS_H_

#include <utility>

#include "gl/gl_functions.h"

namespace pdsm::gl {

// `Traits::Delete(gl, name)` frees one name. Name 0 means "owns nothing".
template <typename Traits>
class GlObject {
 public:
  GlObject() = default;
  // Takes ownership of `name`, made with `gl`.
  GlObject(const GlFunctions* gl, GLuint name) : gl_(gl), name_(name) {}
  ~GlObject() { Reset(); }

  GlObject(const GlObject&) = delete;
  GlObject& operator=(const GlObject&) = delete;
  GlObject(GlObject&& other) noexcept : gl_(other.gl_), name_(std::exchange(other.name_, 0)) {}
  GlObject& operator=(GlObject&& other) noexcept {
    if (this != &other) {
      Reset();
      gl_ = other.gl_;
      name_ = std::exchange(other.name_, 0);
    }
    return *this;
  }

  GLuint name() const { return name_; }
  explicit operator bool() const { return name_ != 0; }

  void Reset() {
    if (name_ != 0) Traits::Delete(*gl_, name_);
    name_ = 0;
  }

 private:
  const GlFunctions* gl_ = nullptr;
  GLuint name_ = 0;
};

struct BufferTraits {
  static void Delete(const GlFunctions& gl, GLuint name) { gl.DeleteBuffers(1, &name); }
};
struct VertexArrayTraits {
  static void Delete(const GlFunctions& gl, GLuint name) { gl.DeleteVertexArrays(1, &name); }
};
struct TextureTraits {
  static void Delete(const GlFunctions& gl, GLuint name) { gl.DeleteTextures(1, &name); }
};
struct FramebufferTraits {
  static void Delete(const GlFunctions& gl, GLuint name) { gl.DeleteFramebuffers(1, &name); }
};
struct ShaderTraits {
  static void Delete(const GlFunctions& gl, GLuint name) { gl.DeleteShader(name); }
};
struct ProgramTraits {
  static void Delete(const GlFunctions& gl, GLuint name) { gl.DeleteProgram(name); }
};

using Buffer = GlObject<BufferTraits>;
using VertexArray = GlObject<VertexArrayTraits>;
using Texture = GlObject<TextureTraits>;
using Framebuffer = GlObject<FramebufferTraits>;
using Shader = GlObject<ShaderTraits>;
using Program = GlObject<ProgramTraits>;

// Factories: REQUIRES a current context made by the driver `gl` was loaded from. A returned
// object owns name 0 only if the driver failed (check glGetError).
inline Buffer MakeBuffer(const GlFunctions& gl) {
  GLuint name = 0;
  gl.GenBuffers(1, &name);
  return Buffer(&gl, name);
}
inline VertexArray MakeVertexArray(const GlFunctions& gl) {
  GLuint name = 0;
  gl.GenVertexArrays(1, &name);
  return VertexArray(&gl, name);
}
inline Texture MakeTexture(const GlFunctions& gl) {
  GLuint name = 0;
  gl.GenTextures(1, &name);
  return Texture(&gl, name);
}
inline Framebuffer MakeFramebuffer(const GlFunctions& gl) {
  GLuint name = 0;
  gl.GenFramebuffers(1, &name);
  return Framebuffer(&gl, name);
}
inline Shader MakeShader(const GlFunctions& gl, GLenum type) {
  return Shader(&gl, gl.CreateShader(type));
}
inline Program MakeProgram(const GlFunctions& gl) { return Program(&gl, gl.CreateProgram()); }

}  // namespace pdsm::gl

#endif  // PDSM_GL_GL_OBJECTS_H_
