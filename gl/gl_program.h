// Building GLSL programs and checking GL errors: one place for the shadow-map
// renderer and the viewer, so a driver's compile or link log always reaches the
// caller the same way.
#ifndef PDSM_GL_GL_PROGRAM_H_
#define PDSM_GL_GL_PROGRAM_H_

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/strings/string_view.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"

namespace pdsm::gl {

// Drains the GL error flags; INTERNAL naming `what` and the first error if any
// was set.
absl::Status CheckGlError(const GlFunctions &gl, absl::string_view what);

// Compiles both stages and links them; INTERNAL with the driver's log naming
// `name` on failure. REQUIRES: a current context.
absl::StatusOr<Program> BuildProgram(const GlFunctions &gl, const char *vertex_source,
                                     const char *fragment_source, absl::string_view name);

}  // namespace pdsm::gl

#endif  // PDSM_GL_GL_PROGRAM_H_
