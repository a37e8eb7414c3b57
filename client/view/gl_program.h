// Building GLSL programs and checking GL errors for the viewer, plus uniform setters by name
// (the viewer sets a few dozen uniforms per frame; looking them up is not what costs).
#ifndef PDSM_CLIENT_VIEW_GL_PROGRAM_H_
#define PDSM_CLIENT_VIEW_GL_PROGRAM_H_

#include <string>

#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "worker/gl/gl_functions.h"
#include "worker/gl/gl_objects.h"

namespace pdsm::view {

// Drains the GL error flags; INTERNAL naming `what` and the first error if any was set.
absl::Status CheckGlError(const gl::GlFunctions& gl, absl::string_view what);

// Compiles and links; INTERNAL with the driver's log naming `name` on failure.
absl::StatusOr<gl::Program> BuildProgram(const gl::GlFunctions& gl, const char* vertex_source,
                                         const char* fragment_source, absl::string_view name);

// Setters on the program in use (glUseProgram). Unknown names (location -1) are ignored, as
// GL does: the compiler drops uniforms a program does not use.
class UniformSetter {
 public:
  UniformSetter(const gl::GlFunctions& gl, GLuint program) : gl_(gl), program_(program) {}
  void Int(const char* name, int value) const;
  void Int2(const char* name, glm::ivec2 value) const;
  void Float(const char* name, float value) const;
  void Vec2(const char* name, glm::vec2 value) const;
  void Vec3(const char* name, glm::vec3 value) const;
  void Mat3(const char* name, const glm::mat3& value) const;
  void Mat4(const char* name, const glm::mat4& value) const;

 private:
  GLint Location(const char* name) const { return gl_.GetUniformLocation(program_, name); }
  const gl::GlFunctions& gl_;
  GLuint program_;
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_GL_PROGRAM_H_
