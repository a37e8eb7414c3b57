#include "gl/gl_program.h"

#include <algorithm>
#include <string>

#include <glm/gtc/type_ptr.hpp>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace pdsm::gl {

namespace {

absl::StatusOr<Shader> Compile(const GlFunctions& gl, GLenum type, const char* source,
                               absl::string_view name) {
  Shader shader = MakeShader(gl, type);
  if (!shader) return absl::InternalError(absl::StrCat("glCreateShader failed for ", name));
  gl.ShaderSource(shader.name(), 1, &source, nullptr);
  gl.CompileShader(shader.name());
  GLint ok = GL_FALSE;
  gl.GetShaderiv(shader.name(), GL_COMPILE_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    gl.GetShaderiv(shader.name(), GL_INFO_LOG_LENGTH, &length);
    std::string log(std::max(length, 1), '\0');
    gl.GetShaderInfoLog(shader.name(), length, nullptr, log.data());
    return absl::InternalError(absl::StrCat("compiling ", name, " failed: ", log.c_str()));
  }
  return shader;
}

}  // namespace

absl::Status CheckGlError(const GlFunctions& gl, absl::string_view what) {
  const GLenum first = gl.GetError();
  if (first == GL_NO_ERROR) return absl::OkStatus();
  for (int i = 0; i < 16 && gl.GetError() != GL_NO_ERROR; ++i) {
  }
  const std::string message = absl::StrFormat("GL error 0x%04x after %s", first, what);
  // Out of memory is the size of the data, not a fault: callers may go on without it.
  if (first == GL_OUT_OF_MEMORY) return absl::ResourceExhaustedError(message + " (out of memory)");
  return absl::InternalError(message);
}

absl::StatusOr<Program> BuildProgram(const GlFunctions& gl, const char* vertex_source,
                                     const char* fragment_source, absl::string_view name) {
  absl::StatusOr<Shader> vertex =
      Compile(gl, GL_VERTEX_SHADER, vertex_source, absl::StrCat(name, " (vertex)"));
  if (!vertex.ok()) return vertex.status();
  absl::StatusOr<Shader> fragment =
      Compile(gl, GL_FRAGMENT_SHADER, fragment_source, absl::StrCat(name, " (fragment)"));
  if (!fragment.ok()) return fragment.status();
  Program program = MakeProgram(gl);
  if (!program) return absl::InternalError("glCreateProgram failed");
  gl.AttachShader(program.name(), vertex->name());
  gl.AttachShader(program.name(), fragment->name());
  gl.LinkProgram(program.name());
  // Detached so the shaders are freed with their wrappers rather than with the
  // program.
  gl.DetachShader(program.name(), vertex->name());
  gl.DetachShader(program.name(), fragment->name());
  GLint ok = GL_FALSE;
  gl.GetProgramiv(program.name(), GL_LINK_STATUS, &ok);
  if (ok != GL_TRUE) {
    GLint length = 0;
    gl.GetProgramiv(program.name(), GL_INFO_LOG_LENGTH, &length);
    std::string log(std::max(length, 1), '\0');
    gl.GetProgramInfoLog(program.name(), length, nullptr, log.data());
    return absl::InternalError(absl::StrCat("linking ", name, " failed: ", log.c_str()));
  }
  if (absl::Status s = CheckGlError(gl, absl::StrCat("building ", name)); !s.ok()) return s;
  return program;
}

void UniformSetter::Int(const char* name, int value) const { gl_.Uniform1i(Location(name), value); }
void UniformSetter::Int2(const char* name, glm::ivec2 value) const {
  gl_.Uniform2i(Location(name), value.x, value.y);
}
void UniformSetter::Float(const char* name, float value) const {
  gl_.Uniform1f(Location(name), value);
}
void UniformSetter::Vec2(const char* name, glm::vec2 value) const {
  gl_.Uniform2f(Location(name), value.x, value.y);
}
void UniformSetter::Vec3(const char* name, glm::vec3 value) const {
  gl_.Uniform3f(Location(name), value.x, value.y, value.z);
}
void UniformSetter::Mat3(const char* name, const glm::mat3& value) const {
  gl_.UniformMatrix3fv(Location(name), 1, GL_FALSE, glm::value_ptr(value));
}
void UniformSetter::Mat4(const char* name, const glm::mat4& value) const {
  gl_.UniformMatrix4fv(Location(name), 1, GL_FALSE, glm::value_ptr(value));
}

}  // namespace pdsm::gl
