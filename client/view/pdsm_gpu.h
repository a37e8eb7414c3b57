// The PDSM on the GPU, in the two levels the thesis proposes (4.2.4): an index texture
// (RG32UI: offset of the pixel's first vertex, vertex count) and one shader storage buffer of
// every vertex (z, A) as float32 -- no fixed maximum depth per pixel.
//
// Precision: the file stores vertices as float32 (docs/pdsm_format.md), so the upload copies
// them bit for bit and loses nothing. What differs from the CPU query is the evaluation: the
// fragment's light-space depth and window position are float32 on the GPU (double on the
// CPU), a relative error of ~6e-8 in depth. docs/viewer.md gives the measured effect.
#ifndef PDSM_CLIENT_VIEW_PDSM_GPU_H_
#define PDSM_CLIENT_VIEW_PDSM_GPU_H_

#include <cstdint>
#include <vector>

#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"

namespace pdsm::view {

struct PdsmGpu {
  gl::Texture index;    // RG32UI, PDSM width x height, row 0 at t_min
  gl::Buffer vertices;  // SSBO: vec2 (z, A) per vertex, std430
  uint64_t index_bytes = 0;
  uint64_t vertex_bytes = 0;
  double upload_seconds = 0;  // CPU packing + GL upload, with glFinish
};

// Index count of a pixel whose tile is not baked yet (a job followed while it runs).
inline constexpr uint32_t kPendingPixel = 0xFFFFFFFFu;

// REQUIRES: a current GL 4.3+ context made by the driver `gl` was loaded from. `pending`
// (empty, or one flag per pixel) marks pixels not baked yet.
// RESOURCE_EXHAUSTED when the vertices exceed GL_MAX_SHADER_STORAGE_BLOCK_SIZE or 2^32, or the
// image GL_MAX_TEXTURE_SIZE; INTERNAL when GL fails.
absl::StatusOr<PdsmGpu> UploadPdsm(const gl::GlFunctions& gl, const PdsmImage& pdsm,
                                   const std::vector<uint8_t>& pending = {});

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_PDSM_GPU_H_
