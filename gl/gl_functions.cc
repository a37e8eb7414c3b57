#include "gl/gl_functions.h"

#include "absl/strings/str_cat.h"

namespace pdsm::gl {

absl::StatusOr<GlFunctions> GlFunctions::Load(GetProcAddressFn get_proc_address) {
  if (get_proc_address == nullptr) {
    return absl::InvalidArgumentError("GlFunctions::Load: get_proc_address is null");
  }
  GlFunctions gl;
#define PDSM_GL_LOAD_MEMBER(type, name)                                               \
  gl.name = reinterpret_cast<type>(get_proc_address("gl" #name));                     \
  if (gl.name == nullptr) {                                                           \
    return absl::NotFoundError(absl::StrCat("GL entry point gl" #name " not found")); \
  }
  PDSM_GL_FUNCTION_LIST(PDSM_GL_LOAD_MEMBER)
#undef PDSM_GL_LOAD_MEMBER
  return gl;
}

}  // namespace pdsm::gl
