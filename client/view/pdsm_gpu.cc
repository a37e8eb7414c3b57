#include "client/view/pdsm_gpu.h"

#include <chrono>
#include <limits>
#include <vector>

#include "absl/strings/str_cat.h"
#include "gl/gl_program.h"

namespace pdsm::view {

absl::StatusOr<PdsmGpu> UploadPdsm(const gl::GlFunctions& gl, const PdsmImage& pdsm,
                                   const std::vector<uint8_t>& pending) {
  const auto start = std::chrono::steady_clock::now();
  const int width = pdsm.header.geometry.width;
  const int height = pdsm.header.geometry.height;
  const uint64_t vertex_count = pdsm.vertices.size();
  GLint max_texture = 0, max_block = 0;
  gl.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
  gl.GetIntegerv(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &max_block);
  if (width > max_texture || height > max_texture) {
    return absl::ResourceExhaustedError(
        absl::StrCat("PDSM of ", width, "x", height, " exceeds GL_MAX_TEXTURE_SIZE ", max_texture));
  }
  // The index holds 32-bit offsets; the block size is what one SSBO binding may address.
  const uint64_t vertex_bytes = vertex_count * 2 * sizeof(float);
  if (vertex_count > std::numeric_limits<uint32_t>::max() ||
      vertex_bytes > static_cast<uint64_t>(static_cast<uint32_t>(max_block))) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "PDSM has ", vertex_count, " vertices (", vertex_bytes,
        " bytes), more than one shader storage buffer holds here (", max_block, " bytes)"));
  }
  std::vector<uint32_t> index(static_cast<size_t>(width) * height * 2);
  for (size_t p = 0; p + 1 < pdsm.offsets.size() && 2 * p < index.size(); ++p) {
    index[2 * p] = static_cast<uint32_t>(pdsm.offsets[p]);
    index[2 * p + 1] = static_cast<uint32_t>(pdsm.offsets[p + 1] - pdsm.offsets[p]);
    if (p < pending.size() && pending[p]) index[2 * p + 1] = kPendingPixel;
  }
  static_assert(sizeof(Vertex) == 2 * sizeof(float), "Vertex is (z, A) float32, std430 vec2");

  PdsmGpu gpu;
  gpu.index = gl::MakeTexture(gl);
  gl.BindTexture(GL_TEXTURE_2D, gpu.index.name());
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  gl.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RG32UI, width, height, 0, GL_RG_INTEGER, GL_UNSIGNED_INT,
                index.data());
  gl.BindTexture(GL_TEXTURE_2D, 0);
  gpu.vertices = gl::MakeBuffer(gl);
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, gpu.vertices.name());
  // An empty buffer cannot be bound; one dummy vertex keeps the binding valid.
  const Vertex dummy{0, 0};
  gl.BufferData(GL_SHADER_STORAGE_BUFFER,
                vertex_count > 0 ? static_cast<GLsizeiptr>(vertex_bytes) : sizeof(Vertex),
                vertex_count > 0 ? static_cast<const void*>(pdsm.vertices.data()) : &dummy,
                GL_STATIC_DRAW);
  gl.BindBuffer(GL_SHADER_STORAGE_BUFFER, 0);
  gl.Finish();
  if (absl::Status s = gl::CheckGlError(gl, "uploading the PDSM"); !s.ok()) return s;
  gpu.index_bytes = index.size() * sizeof(uint32_t);
  gpu.vertex_bytes = vertex_bytes;
  gpu.upload_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return gpu;
}

}  // namespace pdsm::view
