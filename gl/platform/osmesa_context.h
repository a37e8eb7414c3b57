// A headless OpenGL core-profile context from OSMesa (Mesa's llvmpipe), as a move-only RAII
// owner. The context renders into framebuffer objects only; OSMesaMakeCurrent still needs a
// client colour buffer, so the context owns a 1x1 one that is never drawn to.
#ifndef PDSM_GL_PLATFORM_OSMESA_CONTEXT_H_
#define PDSM_GL_PLATFORM_OSMESA_CONTEXT_H_

#include <cstdint>
#include <memory>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "gl/gl_functions.h"

struct osmesa_context;  // <GL/osmesa.h>'s OSMesaContext is `osmesa_context*`

namespace pdsm::gl {

// llvmpipe rasterizes with LP_NUM_THREADS helper threads per context (by default one per
// core). A process that already runs one context per core on its own threads only
// oversubscribes the cores with them and pays their memory (measured in docs/performance.md,
// "GL memory"): this sets LP_NUM_THREADS so that contexts x threads stays at the core count
// (0: llvmpipe rasterizes on the calling thread). Call before the first context is created;
// an LP_NUM_THREADS the user set is left alone. Returns the value in effect.
int ShareCoresBetweenContexts(int contexts);

class OsMesaContext {
 public:
  // Creates a core-profile context, GL 4.5 or else 3.3, with no depth/stencil/accum buffers,
  // and makes it current on the calling thread. INTERNAL when OSMesa refuses both versions or
  // cannot make it current.
  static absl::StatusOr<OsMesaContext> Create();

  OsMesaContext(const OsMesaContext&) = delete;
  OsMesaContext& operator=(const OsMesaContext&) = delete;
  OsMesaContext(OsMesaContext&& other) noexcept;
  OsMesaContext& operator=(OsMesaContext&& other) noexcept;
  // Releases the context (first unbinding it if current on this thread). GL objects made in
  // it must be gone by then.
  ~OsMesaContext();

  // Makes this context current on the calling thread (a no-op if it already is). A context
  // must not be current on two threads at once.
  absl::Status MakeCurrent() const;
  bool IsCurrent() const;
  // Unbinds this context from the calling thread if it is current there (else a no-op), so
  // that another thread may make it current next.
  void Release() const;

  // The version requested and granted (4.5 or 3.3).
  int major_version() const { return major_version_; }
  int minor_version() const { return minor_version_; }

  // OSMesaGetProcAddress, as a GetProcAddressFn for GlFunctions::Load.
  static GlProc GetProcAddress(const char* name);

 private:
  OsMesaContext(osmesa_context* context, int major_version, int minor_version);
  void Destroy();

  osmesa_context* context_ = nullptr;
  // Heap-held so its address survives moves: OSMesa keeps the pointer while current.
  std::unique_ptr<uint8_t[]> colour_buffer_;
  int major_version_ = 0;
  int minor_version_ = 0;
};

}  // namespace pdsm::gl

#endif  // PDSM_GL_PLATFORM_OSMESA_CONTEXT_H_
