#include "gl/platform/osmesa_context.h"

#include <algorithm>
#include <cstdlib>
#include <string>
#include <thread>

#include <GL/osmesa.h>

#include <utility>

#include "absl/strings/str_cat.h"

namespace pdsm::gl {

int ShareCoresBetweenContexts(int contexts) {
  if (const char* set = std::getenv("LP_NUM_THREADS"); set != nullptr && *set != '\0') {
    return std::atoi(set);
  }
  const int cores = static_cast<int>(std::max(1u, std::thread::hardware_concurrency()));
  const int per_context = contexts >= cores ? 0 : cores / std::max(1, contexts);
  setenv("LP_NUM_THREADS", std::to_string(per_context).c_str(), /*overwrite=*/1);
  return per_context;
}

namespace {

// OSMesaMakeCurrent refuses a null buffer; 1x1 RGBA8 is the smallest it accepts.
constexpr int kColourBufferSize = 1;

OSMesaContext CreateCoreContext(int major, int minor) {
  // (name, value) pairs.
  // clang-format off
  const int attribs[] = {
      OSMESA_FORMAT, OSMESA_RGBA,
      OSMESA_DEPTH_BITS, 0,  // all rendering goes to FBOs
      OSMESA_STENCIL_BITS, 0,
      OSMESA_ACCUM_BITS, 0,
      OSMESA_PROFILE, OSMESA_CORE_PROFILE,
      OSMESA_CONTEXT_MAJOR_VERSION, major,
      OSMESA_CONTEXT_MINOR_VERSION, minor,
      0,
  };
  // clang-format on
  return OSMesaCreateContextAttribs(attribs, nullptr);
}

}  // namespace

absl::StatusOr<OsMesaContext> OsMesaContext::Create() {
  int major = 4, minor = 5;  // 4.5: glClipControl for reversed-Z
  OSMesaContext context = CreateCoreContext(major, minor);
  if (context == nullptr) {
    major = 3;
    minor = 3;
    context = CreateCoreContext(major, minor);
  }
  if (context == nullptr) {
    return absl::InternalError("OSMesaCreateContextAttribs failed for core profile 4.5 and 3.3");
  }
  OsMesaContext result(context, major, minor);
  if (absl::Status status = result.MakeCurrent(); !status.ok()) return status;
  return result;
}

OsMesaContext::OsMesaContext(osmesa_context* context, int major_version, int minor_version)
    : context_(context),
      colour_buffer_(new uint8_t[4 * kColourBufferSize * kColourBufferSize]()),
      major_version_(major_version),
      minor_version_(minor_version) {}

OsMesaContext::OsMesaContext(OsMesaContext&& other) noexcept
    : context_(std::exchange(other.context_, nullptr)),
      colour_buffer_(std::move(other.colour_buffer_)),
      major_version_(other.major_version_),
      minor_version_(other.minor_version_) {}

OsMesaContext& OsMesaContext::operator=(OsMesaContext&& other) noexcept {
  if (this != &other) {
    Destroy();
    context_ = std::exchange(other.context_, nullptr);
    colour_buffer_ = std::move(other.colour_buffer_);
    major_version_ = other.major_version_;
    minor_version_ = other.minor_version_;
  }
  return *this;
}

OsMesaContext::~OsMesaContext() { Destroy(); }

void OsMesaContext::Destroy() {
  if (context_ == nullptr) return;
  Release();  // so that this thread is not left with a dangling current context
  OSMesaDestroyContext(context_);
  context_ = nullptr;
}

absl::Status OsMesaContext::MakeCurrent() const {
  if (context_ == nullptr) return absl::FailedPreconditionError("OsMesaContext is empty");
  if (IsCurrent()) return absl::OkStatus();
  if (!OSMesaMakeCurrent(context_, colour_buffer_.get(), GL_UNSIGNED_BYTE, kColourBufferSize,
                         kColourBufferSize)) {
    return absl::InternalError(absl::StrCat("OSMesaMakeCurrent failed (GL ", major_version_, ".",
                                            minor_version_, " core context)"));
  }
  return absl::OkStatus();
}

void OsMesaContext::Release() const {
  if (IsCurrent()) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
}

bool OsMesaContext::IsCurrent() const {
  return context_ != nullptr && OSMesaGetCurrentContext() == context_;
}

GlProc OsMesaContext::GetProcAddress(const char* name) { return OSMesaGetProcAddress(name); }

}  // namespace pdsm::gl
