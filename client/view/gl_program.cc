#include "client/view/gl_program.h"

#include <algorithm>
#include <glm/gtc/type_ptr.hpp>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"

namespace pdsm::view {

void UniformSetter::Int(const char *name, int value) const { gl_.Uniform1i(Location(name), value); }
void UniformSetter::Int2(const char *name, glm::ivec2 value) const {
  gl_.Uniform2i(Location(name), value.x, value.y);
}
void UniformSetter::Float(const char *name, float value) const {
  gl_.Uniform1f(Location(name), value);
}
void UniformSetter::Vec2(const char *name, glm::vec2 value) const {
  gl_.Uniform2f(Location(name), value.x, value.y);
}
void UniformSetter::Vec3(const char *name, glm::vec3 value) const {
  gl_.Uniform3f(Location(name), value.x, value.y, value.z);
}
void UniformSetter::Mat3(const char *name, const glm::mat3 &value) const {
  gl_.UniformMatrix3fv(Location(name), 1, GL_FALSE, glm::value_ptr(value));
}
void UniformSetter::Mat4(const char *name, const glm::mat4 &value) const {
  gl_.UniformMatrix4fv(Location(name), 1, GL_FALSE, glm::value_ptr(value));
}

}  // namespace pdsm::view
