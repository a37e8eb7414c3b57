// Building GLSL programs, setting their uniforms and checking GL errors: one place for the
// bake's shadow-map renderer and the viewer, so a driver's compile or link log always reaches
// the caller the same way.
#ifndef PDSM_GL_GL_PROGRAM_H_
#define PDSM_GL_GL_PROGRAM_H_

#include <glm/glm.hpp>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"

namespace pdsm::gl {

// Drains the GL error flags; INTERNAL naming `what` and the first error if any
// was set.
absl::Status CheckGlError(const GlFunctions& gl, absl::string_view what);

// Compiles both stages and links them; INTERNAL with the driver's log naming
// `name` on failure. REQUIRES: a current context.
absl::StatusOr<Program> BuildProgram(const GlFunctions& gl, const char* vertex_source,
                                     const char* fragment_source, absl::string_view name);

// Uniform setters by name on the program in use (glUseProgram), for callers that set a few
// dozen uniforms per frame (the viewer): looking them up is not what costs there; a hot loop
// caches glGetUniformLocation instead. Unknown names (location -1) are ignored, as GL does:
// the compiler drops uniforms a program does not use. REQUIRES: `gl` outlives the setter.
class UniformSetter {
 public:
  UniformSetter(const GlFunctions& gl, GLuint program) : gl_(gl), program_(program) {}
  void Int(const char* name, int value) const;
  void Int2(const char* name, glm::ivec2 value) const;
  void Float(const char* name, float value) const;
  void Vec2(const char* name, glm::vec2 value) const;
  void Vec3(const char* name, glm::vec3 value) const;
  void Mat3(const char* name, const glm::mat3& value) const;
  void Mat4(const char* name, const glm::mat4& value) const;

 private:
  GLint Location(const char* name) const { return gl_.GetUniformLocation(program_, name); }
  const GlFunctions& gl_;
  GLuint program_;
};

}  // namespace pdsm::gl

#endif  // PDSM_GL_GL_PROGRAM_H_
