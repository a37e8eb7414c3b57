// Uniform setters by name for the viewer (it sets a few dozen uniforms per frame; looking
// them up is not what costs).
#ifndef PDSM_CLIENT_VIEW_GL_PROGRAM_H_
#define PDSM_CLIENT_VIEW_GL_PROGRAM_H_

#include <glm/glm.hpp>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"
#include "gl/gl_program.h"

namespace pdsm::view {

// The GL layer's program building and error checks (gl/gl_program.h).
using gl::BuildProgram;
using gl::CheckGlError;

// Setters on the program in use (glUseProgram). Unknown names (location -1) are
// ignored, as GL does: the compiler drops uniforms a program does not use.
class UniformSetter {
 public:
  UniformSetter(const gl::GlFunctions &gl, GLuint program) : gl_(gl), program_(program) {}
  void Int(const char *name, int value) const;
  void Int2(const char *name, glm::ivec2 value) const;
  void Float(const char *name, float value) const;
  void Vec2(const char *name, glm::vec2 value) const;
  void Vec3(const char *name, glm::vec3 value) const;
  void Mat3(const char *name, const glm::mat3 &value) const;
  void Mat4(const char *name, const glm::mat4 &value) const;

 private:
  GLint Location(const char *name) const { return gl_.GetUniformLocation(program_, name); }
  const gl::GlFunctions &gl_;
  GLuint program_;
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_GL_PROGRAM_H_
