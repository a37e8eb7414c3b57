#include "worker/shadow_map_renderer.h"

#include <algorithm>
#include <array>
#include <climits>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"
#include "gl/gl_program.h"
#include "gl/platform/osmesa_context.h"
#include "spdlog/spdlog.h"
#include "worker/shadow_map_shaders.h"  // generated: the embedded GLSL sources

namespace pdsm {
namespace {

using gl::CheckGlError;
using gl::GlFunctions;

// Pieces beyond this are not worth their memory (an 8192^2 piece is 512 MiB of attachments).
constexpr int kMaxPieceSizeCap = 8192;

// Triangles drawn between flushes. llvmpipe bins a frame's triangles into a scene that it
// rasterizes at the flush; one draw of the dragon's 202k triangles built a ~28 MiB scene per
// context, allocated and faulted in for every map. Flushing every 16k triangles keeps the
// scene small and warm in cache: measured on the dragon (512^2/256, 2 threads, medians of 2
// interleaved) 7.0 instead of 7.9 CPU-s and 223 instead of 269 MiB peak RSS; at 1024^2/256
// 10.3 instead of 17.0 CPU-s (docs/performance.md, "Flushing the scene"). The depth test
// makes the image independent of the batches, so the maps do not change.
constexpr int64_t kTrianglesPerFlush = 16384;

spdlog::logger& Logger() {
  static const std::shared_ptr<spdlog::logger> logger = spdlog::default_logger()->clone("gl");
  return *logger;
}

// The shadow-map program; `alpha_test`: the alpha-tested variant (PDSM_ALPHA_TEST defined
// right after the #version line, which must stay first).
absl::StatusOr<gl::Program> LinkShadowMapProgram(const GlFunctions& gl, bool alpha_test) {
  if (!alpha_test) {
    return gl::BuildProgram(gl, kShadowMapVertexShader, kShadowMapFragmentShader,
                            "the shadow-map program (shadow_map.vert, shadow_map.frag)");
  }
  const auto with_define = [](absl::string_view source) {
    const size_t line_end = source.find('\n') + 1;
    return absl::StrCat(source.substr(0, line_end), "#define PDSM_ALPHA_TEST 1\n",
                        source.substr(line_end));
  };
  const std::string vertex = with_define(kShadowMapVertexShader);
  const std::string fragment = with_define(kShadowMapFragmentShader);
  return gl::BuildProgram(gl, vertex.c_str(), fragment.c_str(),
                          "the alpha-tested shadow-map program (shadow_map.vert, "
                          "shadow_map.frag with PDSM_ALPHA_TEST)");
}

GLint WrapMode(TextureWrap wrap) {
  switch (wrap) {
    case TextureWrap::kClampToEdge:
      return GL_CLAMP_TO_EDGE;
    case TextureWrap::kMirroredRepeat:
      return GL_MIRRORED_REPEAT;
    case TextureWrap::kRepeat:
      break;
  }
  return GL_REPEAT;
}

absl::Status ValidateCamera(const ShadowMapCamera& camera) {
  const ShadowMapLattice& lattice = camera.lattice;
  if (!(std::isfinite(lattice.pitch_s) && lattice.pitch_s > 0 && std::isfinite(lattice.pitch_t) &&
        lattice.pitch_t > 0 && std::isfinite(lattice.s_origin) &&
        std::isfinite(lattice.t_origin))) {
    return absl::InvalidArgumentError("camera.lattice: pitches must be finite and > 0");
  }
  if (camera.window.width < 0 || camera.window.height < 0) {
    return absl::InvalidArgumentError("camera.window: negative width or height");
  }
  if (!std::isfinite(camera.sample.x) || !std::isfinite(camera.sample.y)) {
    return absl::InvalidArgumentError("camera.sample is not finite");
  }
  if (!std::isfinite(camera.depth_bias) || !std::isfinite(camera.slope_bias) ||
      !std::isfinite(camera.footprint_scale)) {
    return absl::InvalidArgumentError("camera bias terms must be finite");
  }
  if (!(std::isfinite(camera.z_clip_near) && camera.z_clip_near > 0) &&
      camera.projection == Projection::kPerspective) {
    return absl::InvalidArgumentError("camera.z_clip_near must be finite and > 0 (perspective)");
  }
  if (camera.projection == Projection::kOrthographic &&
      !(std::isfinite(camera.z_clip_near) && std::isfinite(camera.z_clip_far) &&
        camera.z_clip_far > camera.z_clip_near)) {
    return absl::InvalidArgumentError(
        "camera.z_clip_far must be finite and > z_clip_near (orthographic)");
  }
  return absl::OkStatus();
}

class OsMesaShadowMapRenderer final : public ShadowMapRenderer {
 public:
  OsMesaShadowMapRenderer(gl::OsMesaContext context, const GlFunctions& gl)
      : context_(std::move(context)), gl_(gl) {}
  // Deleting GL names needs this context current (another renderer may have been made
  // current on this thread since).
  ~OsMesaShadowMapRenderer() override { (void)context_.MakeCurrent(); }

  OsMesaShadowMapRenderer(const OsMesaShadowMapRenderer&) = delete;
  OsMesaShadowMapRenderer& operator=(const OsMesaShadowMapRenderer&) = delete;

  absl::Status Init(const Options& options);
  using ShadowMapRenderer::SetGeometry;
  absl::Status SetGeometry(std::span<const glm::vec3> positions_light,
                           std::span<const uint32_t> indices,
                           std::span<const glm::vec2> uvs) override;
  absl::Status SetMasks(std::span<const std::shared_ptr<const AlphaMask>> masks) override;
  absl::Status Render(const ShadowMapCamera& camera, std::vector<float>* depth) override;
  absl::Status Render(const ShadowMapCamera& camera, std::span<const DrawRange> ranges,
                      std::vector<float>* depth) override;
  void LeaveThread() override { context_.Release(); }

 private:
  struct UniformLocations {
    GLint clip_from_light = -1, depth_bias = -1, slope_bias = -1, footprint_scale = -1,
          orthographic = -1, z_clip_near = -1, z_clip_far = -1;
    GLint alpha_mask = -1, alpha_cutoff = -1;  // the alpha-tested program only
  };
  // A linked program and where its uniforms are.
  struct ShadowMapProgram {
    gl::Program program;
    UniformLocations uniforms;
  };
  absl::StatusOr<ShadowMapProgram> MakeProgram(bool alpha_test);
  // Sets the camera's uniforms on `p` (made current).
  void SetCameraUniforms(const ShadowMapProgram& p, const ShadowMapCamera& camera);

  absl::Status ChoosePieceSize(int requested);
  absl::Status EnsureTarget(int width, int height);
  void SetPipelineState(const ShadowMapCamera& camera);
  absl::Status RenderPiece(const ShadowMapCamera& camera, const ShadowMapWindow& piece,
                           int row_length, float* out);
  // Every triangle, or those of the ranges, as MultiDrawElements' counts and byte offsets.
  void SetDrawList(std::span<const DrawRange> ranges);

  gl::OsMesaContext context_;  // first member: destroyed after every GL object below
  GlFunctions gl_;
  bool has_clip_control_ = false;
  int max_piece_size_ = 0;
  ShadowMapProgram opaque_;
  std::optional<ShadowMapProgram> alpha_tested_;  // made by the first SetMasks with masks
  std::vector<gl::Texture> mask_textures_;        // SetMasks' masks, in order
  std::vector<float> mask_cutoffs_;
  gl::VertexArray vertex_array_;
  gl::Buffer vertex_buffer_;
  gl::Buffer uv_buffer_;
  gl::Buffer index_buffer_;
  GLsizei index_count_ = 0;
  bool has_uvs_ = false;
  std::vector<GLsizei> draw_counts_;  // the current Render's draw list
  std::vector<const void*> draw_offsets_;
  std::vector<uint16_t> draw_masks_;  // each draw's DrawRange::mask
  // End (exclusive) in the draw list of each run of at most kTrianglesPerFlush triangles.
  std::vector<size_t> flush_ends_;
  // Render target, grown (never shrunk) to the largest piece rendered so far.
  gl::Framebuffer framebuffer_;
  gl::Texture biased_depth_;    // GL_R32F: biased light-space z, the output
  gl::Texture reversed_depth_;  // GL_DEPTH_COMPONENT32F: reversed depth for the test
  int target_width_ = 0, target_height_ = 0;
};

absl::Status OsMesaShadowMapRenderer::Init(const Options& options) {
  GLint major = 0, minor = 0;
  gl_.GetIntegerv(GL_MAJOR_VERSION, &major);
  gl_.GetIntegerv(GL_MINOR_VERSION, &minor);
  // Mesa hands out stubs for any name, so the version decides whether glClipControl is real.
  has_clip_control_ = major > 4 || (major == 4 && minor >= 5);
  if (absl::Status status = ChoosePieceSize(options.max_piece_size); !status.ok()) return status;

  absl::StatusOr<ShadowMapProgram> program = MakeProgram(/*alpha_test=*/false);
  if (!program.ok()) return program.status();
  opaque_ = *std::move(program);

  vertex_array_ = gl::MakeVertexArray(gl_);
  vertex_buffer_ = gl::MakeBuffer(gl_);
  uv_buffer_ = gl::MakeBuffer(gl_);
  index_buffer_ = gl::MakeBuffer(gl_);
  framebuffer_ = gl::MakeFramebuffer(gl_);
  gl_.BindVertexArray(vertex_array_.name());
  gl_.BindBuffer(GL_ARRAY_BUFFER, vertex_buffer_.name());
  gl_.EnableVertexAttribArray(0);
  gl_.VertexAttribPointer(0, 3, GL_FLOAT, GL_FALSE, sizeof(glm::vec3), nullptr);
  gl_.BindBuffer(GL_ELEMENT_ARRAY_BUFFER, index_buffer_.name());  // recorded in the VAO
  if (absl::Status status = CheckGlError(gl_, "creating the vertex array"); !status.ok()) {
    return status;
  }
  Logger().debug("shadow-map renderer: GL {}.{} ({}), max piece {}", major, minor,
                 reinterpret_cast<const char*>(gl_.GetString(GL_RENDERER)), max_piece_size_);
  return absl::OkStatus();
}

absl::StatusOr<OsMesaShadowMapRenderer::ShadowMapProgram> OsMesaShadowMapRenderer::MakeProgram(
    bool alpha_test) {
  absl::StatusOr<gl::Program> program = LinkShadowMapProgram(gl_, alpha_test);
  if (!program.ok()) return program.status();
  ShadowMapProgram out;
  out.program = *std::move(program);
  const auto location = [&](const char* name) {
    return gl_.GetUniformLocation(out.program.name(), name);
  };
  UniformLocations& u = out.uniforms;
  u.clip_from_light = location("clip_from_light");
  u.depth_bias = location("depth_bias");
  u.slope_bias = location("slope_bias");
  u.footprint_scale = location("footprint_scale");
  u.orthographic = location("orthographic");
  u.z_clip_near = location("z_clip_near");
  u.z_clip_far = location("z_clip_far");
  u.alpha_mask = location("alpha_mask");
  u.alpha_cutoff = location("alpha_cutoff");
  return out;
}

absl::Status OsMesaShadowMapRenderer::ChoosePieceSize(int requested) {
  if (requested < 0 || requested == 1) {
    return absl::InvalidArgumentError(
        absl::StrCat("options.max_piece_size must be 0 or >= 2, got ", requested));
  }
  GLint max_texture = 0;
  GLint max_viewport[2] = {0, 0};
  gl_.GetIntegerv(GL_MAX_TEXTURE_SIZE, &max_texture);
  gl_.GetIntegerv(GL_MAX_VIEWPORT_DIMS, max_viewport);
  int size = std::min({kMaxPieceSizeCap, max_texture, max_viewport[0], max_viewport[1]});
  if (requested > 0) size = std::min(size, requested);
  // Even, so every piece origin is even: dFdx/dFdy pair texels in 2x2 quads anchored at the
  // viewport origin, and the slope bias must not depend on how a window was split.
  max_piece_size_ = size & ~1;
  if (max_piece_size_ < 2) {
    return absl::InternalError(absl::StrCat("GL limits allow no render target: ", size));
  }
  return CheckGlError(gl_, "querying GL limits");
}

absl::Status OsMesaShadowMapRenderer::SetGeometry(std::span<const glm::vec3> positions_light,
                                                  std::span<const uint32_t> indices,
                                                  std::span<const glm::vec2> uvs) {
  if (!uvs.empty() && uvs.size() != positions_light.size()) {
    return absl::InvalidArgumentError(
        absl::StrCat("uvs: ", uvs.size(), " for ", positions_light.size(), " positions"));
  }
  for (size_t i = 0; i < uvs.size(); ++i) {
    if (!std::isfinite(uvs[i].x) || !std::isfinite(uvs[i].y)) {
      return absl::InvalidArgumentError(absl::StrCat("uvs[", i, "] is not finite"));
    }
  }
  if (indices.size() % 3 != 0) {
    return absl::InvalidArgumentError(
        absl::StrCat("indices: size ", indices.size(), " is not a multiple of 3"));
  }
  if (indices.size() > static_cast<size_t>(INT_MAX)) {
    return absl::InvalidArgumentError("indices: more than INT_MAX indices");
  }
  for (size_t i = 0; i < positions_light.size(); ++i) {
    const glm::vec3& p = positions_light[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      return absl::InvalidArgumentError(absl::StrCat("positions_light[", i, "] is not finite"));
    }
  }
  for (size_t i = 0; i < indices.size(); ++i) {
    if (indices[i] >= positions_light.size()) {
      return absl::InvalidArgumentError(absl::StrCat("indices[", i, "] = ", indices[i],
                                                     " >= ", positions_light.size(), " positions"));
    }
  }
  if (absl::Status status = context_.MakeCurrent(); !status.ok()) return status;
  gl_.BindVertexArray(vertex_array_.name());
  gl_.BindBuffer(GL_ARRAY_BUFFER, vertex_buffer_.name());
  gl_.BufferData(GL_ARRAY_BUFFER, positions_light.size_bytes(), positions_light.data(),
                 GL_STATIC_DRAW);
  gl_.BufferData(GL_ELEMENT_ARRAY_BUFFER, indices.size_bytes(), indices.data(), GL_STATIC_DRAW);
  has_uvs_ = !uvs.empty();
  if (has_uvs_) {
    gl_.BindBuffer(GL_ARRAY_BUFFER, uv_buffer_.name());
    gl_.BufferData(GL_ARRAY_BUFFER, uvs.size_bytes(), uvs.data(), GL_STATIC_DRAW);
    gl_.EnableVertexAttribArray(1);
    gl_.VertexAttribPointer(1, 2, GL_FLOAT, GL_FALSE, sizeof(glm::vec2), nullptr);
  } else {
    gl_.DisableVertexAttribArray(1);
  }
  index_count_ = static_cast<GLsizei>(indices.size());
  if (absl::Status status = CheckGlError(gl_, "uploading geometry"); !status.ok()) {
    index_count_ = 0;  // the buffers' contents are unknown; draw nothing rather than garbage
    has_uvs_ = false;
    return status;
  }
  return absl::OkStatus();
}

absl::Status OsMesaShadowMapRenderer::SetMasks(
    std::span<const std::shared_ptr<const AlphaMask>> masks) {
  for (size_t k = 0; k < masks.size(); ++k) {
    if (masks[k] == nullptr || !masks[k]->Valid()) {
      return absl::InvalidArgumentError(absl::StrCat("masks[", k, "] is not a valid mask"));
    }
  }
  if (absl::Status status = context_.MakeCurrent(); !status.ok()) return status;
  mask_textures_.clear();
  mask_cutoffs_.clear();
  if (masks.empty()) return absl::OkStatus();
  if (!alpha_tested_) {
    absl::StatusOr<ShadowMapProgram> program = MakeProgram(/*alpha_test=*/true);
    if (!program.ok()) return program.status();
    alpha_tested_ = *std::move(program);
  }
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 1);  // rows of R8 texels are not 4-byte multiples
  for (const auto& mask : masks) {
    gl::Texture texture = gl::MakeTexture(gl_);
    gl_.BindTexture(GL_TEXTURE_2D, texture.name());
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAX_LEVEL, 0);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, WrapMode(mask->wrap_u));
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, WrapMode(mask->wrap_v));
    // Row 0 (the image's top, v = 0) at texture t = 0: UVs index the image as glTF does.
    gl_.TexImage2D(GL_TEXTURE_2D, 0, GL_R8, mask->width, mask->height, 0, GL_RED, GL_UNSIGNED_BYTE,
                   mask->alpha.data());
    mask_textures_.push_back(std::move(texture));
    mask_cutoffs_.push_back(mask->cutoff);
  }
  gl_.BindTexture(GL_TEXTURE_2D, 0);
  gl_.PixelStorei(GL_UNPACK_ALIGNMENT, 4);
  if (absl::Status status =
          CheckGlError(gl_, absl::StrCat("uploading ", masks.size(), " alpha masks"));
      !status.ok()) {
    mask_textures_.clear();
    mask_cutoffs_.clear();
    return status;
  }
  return absl::OkStatus();
}

absl::Status OsMesaShadowMapRenderer::EnsureTarget(int width, int height) {
  if (width <= target_width_ && height <= target_height_) return absl::OkStatus();
  const int new_width = std::max(width, target_width_);
  const int new_height = std::max(height, target_height_);
  biased_depth_ = gl::MakeTexture(gl_);
  reversed_depth_ = gl::MakeTexture(gl_);
  const auto allocate = [&](const gl::Texture& texture, GLint internal_format, GLenum format) {
    gl_.BindTexture(GL_TEXTURE_2D, texture.name());
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl_.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl_.TexImage2D(GL_TEXTURE_2D, 0, internal_format, new_width, new_height, 0, format, GL_FLOAT,
                   nullptr);
  };
  allocate(biased_depth_, GL_R32F, GL_RED);
  allocate(reversed_depth_, GL_DEPTH_COMPONENT32F, GL_DEPTH_COMPONENT);
  gl_.BindTexture(GL_TEXTURE_2D, 0);
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.name());
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D,
                           biased_depth_.name(), 0);
  gl_.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D,
                           reversed_depth_.name(), 0);
  const GLenum draw_buffer = GL_COLOR_ATTACHMENT0;
  gl_.DrawBuffers(1, &draw_buffer);
  gl_.ReadBuffer(GL_COLOR_ATTACHMENT0);
  const std::string what =
      absl::StrCat("allocating a ", new_width, "x", new_height, " R32F + D32F render target");
  if (absl::Status status = CheckGlError(gl_, what); !status.ok()) {
    target_width_ = target_height_ = 0;
    return status;
  }
  const GLenum completeness = gl_.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (completeness != GL_FRAMEBUFFER_COMPLETE) {
    target_width_ = target_height_ = 0;
    return absl::InternalError(
        absl::StrFormat("framebuffer incomplete (0x%04x) after %s", completeness, what));
  }
  target_width_ = new_width;
  target_height_ = new_height;
  return absl::OkStatus();
}

// All fixed-function state is set on every Render: nothing relies on what an earlier call
// (or another user of this context) left behind.
void OsMesaShadowMapRenderer::SetPipelineState(const ShadowMapCamera& camera) {
  gl_.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.name());
  gl_.BindVertexArray(vertex_array_.name());
  // Reversed-Z: clip z / w in [0, 1], nearer is larger, cleared to 0 (beyond everything).
  if (has_clip_control_) gl_.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  gl_.Enable(GL_DEPTH_TEST);
  gl_.DepthFunc(GL_GREATER);
  gl_.DepthMask(GL_TRUE);
  gl_.Enable(GL_SCISSOR_TEST);  // clears touch only the piece, not the whole cached target
  gl_.Disable(GL_CULL_FACE);    // both sides of a caster cast
  gl_.Disable(GL_BLEND);
  gl_.PixelStorei(GL_PACK_ALIGNMENT, 4);
  if (alpha_tested_ && !mask_textures_.empty()) {
    gl_.UseProgram(alpha_tested_->program.name());
    SetCameraUniforms(*alpha_tested_, camera);
    gl_.Uniform1i(alpha_tested_->uniforms.alpha_mask, 0);  // texture unit 0
    gl_.ActiveTexture(GL_TEXTURE0);
  }
  gl_.UseProgram(opaque_.program.name());
  SetCameraUniforms(opaque_, camera);
}

void OsMesaShadowMapRenderer::SetCameraUniforms(const ShadowMapProgram& p,
                                                const ShadowMapCamera& camera) {
  const UniformLocations& u = p.uniforms;
  gl_.Uniform1f(u.depth_bias, static_cast<float>(camera.depth_bias));
  gl_.Uniform1f(u.slope_bias, static_cast<float>(camera.slope_bias));
  gl_.Uniform1f(u.footprint_scale, static_cast<float>(camera.footprint_scale));
  gl_.Uniform1i(u.orthographic, camera.projection == Projection::kOrthographic);
  gl_.Uniform1f(u.z_clip_near, static_cast<float>(camera.z_clip_near));
  gl_.Uniform1f(u.z_clip_far, static_cast<float>(camera.z_clip_far));
}

absl::Status OsMesaShadowMapRenderer::RenderPiece(const ShadowMapCamera& camera,
                                                  const ShadowMapWindow& piece, int row_length,
                                                  float* out) {
  if (absl::Status status = EnsureTarget(piece.width, piece.height); !status.ok()) return status;
  gl_.Viewport(0, 0, piece.width, piece.height);
  gl_.Scissor(0, 0, piece.width, piece.height);
  const float no_caster[4] = {std::numeric_limits<float>::infinity(), 0, 0, 0};
  const float beyond_everything = 0.0f;
  gl_.ClearBufferfv(GL_COLOR, 0, no_caster);
  gl_.ClearBufferfv(GL_DEPTH, 0, &beyond_everything);
  if (!draw_counts_.empty()) {
    const std::array<float, 16> clip_from_light =
        ShadowMapClipFromLight(camera, piece, has_clip_control_);
    const bool any_masked =
        std::any_of(draw_masks_.begin(), draw_masks_.end(), [](uint16_t k) { return k != 0; });
    if (any_masked) {
      gl_.UseProgram(alpha_tested_->program.name());
      gl_.UniformMatrix4fv(alpha_tested_->uniforms.clip_from_light, 1, GL_FALSE,
                           clip_from_light.data());
    }
    gl_.UseProgram(opaque_.program.name());
    gl_.UniformMatrix4fv(opaque_.uniforms.clip_from_light, 1, GL_FALSE, clip_from_light.data());
    uint16_t current_mask = 0;
    size_t begin = 0;
    for (const size_t end : flush_ends_) {
      // Runs of draws with one mask: one program and texture each (the draw list never puts
      // opaque and masked triangles in one draw).
      for (size_t run = begin; run < end;) {
        size_t run_end = run + 1;
        while (run_end < end && draw_masks_[run_end] == draw_masks_[run]) ++run_end;
        const uint16_t mask = draw_masks_[run];
        if (mask != current_mask) {
          if (mask == 0) {
            gl_.UseProgram(opaque_.program.name());
          } else {
            if (current_mask == 0) gl_.UseProgram(alpha_tested_->program.name());
            gl_.BindTexture(GL_TEXTURE_2D, mask_textures_[mask - 1].name());
            gl_.Uniform1f(alpha_tested_->uniforms.alpha_cutoff, mask_cutoffs_[mask - 1]);
          }
          current_mask = mask;
        }
        gl_.MultiDrawElements(GL_TRIANGLES, draw_counts_.data() + run, GL_UNSIGNED_INT,
                              draw_offsets_.data() + run, static_cast<GLsizei>(run_end - run));
        run = run_end;
      }
      gl_.Flush();
      begin = end;
    }
    if (current_mask != 0) {
      gl_.BindTexture(GL_TEXTURE_2D, 0);
      gl_.UseProgram(opaque_.program.name());
    }
  }
  // Straight into the output: rows are `row_length` apart there; GL's bottom row (lowest t)
  // is the output's row 0.
  gl_.PixelStorei(GL_PACK_ROW_LENGTH, row_length);
  gl_.ReadPixels(0, 0, piece.width, piece.height, GL_RED, GL_FLOAT, out);
  gl_.PixelStorei(GL_PACK_ROW_LENGTH, 0);
  return CheckGlError(gl_, absl::StrCat("rendering piece at (", piece.x0, ", ", piece.y0, ") ",
                                        piece.width, "x", piece.height));
}

void OsMesaShadowMapRenderer::SetDrawList(std::span<const DrawRange> ranges) {
  draw_counts_.clear();
  draw_offsets_.clear();
  draw_masks_.clear();
  flush_ends_.clear();
  int64_t in_run = 0;  // triangles since the last flush
  const auto add = [&](uint64_t first_triangle, int64_t triangles, uint16_t mask) {
    const uintptr_t offset = first_triangle * 3 * sizeof(uint32_t);
    // Adjacent ranges of one mask are one draw, unless a flush falls between them.
    if (in_run > 0 && draw_masks_.back() == mask &&
        reinterpret_cast<uintptr_t>(draw_offsets_.back()) + draw_counts_.back() * 4 == offset) {
      draw_counts_.back() += static_cast<GLsizei>(3 * triangles);
    } else {
      draw_counts_.push_back(static_cast<GLsizei>(3 * triangles));
      draw_offsets_.push_back(reinterpret_cast<const void*>(offset));
      draw_masks_.push_back(mask);
    }
    in_run += triangles;
    if (in_run == kTrianglesPerFlush) {
      flush_ends_.push_back(draw_counts_.size());
      in_run = 0;
    }
  };
  for (const DrawRange& r : ranges) {
    uint64_t first = r.first_triangle;
    int64_t left = r.triangle_count;
    while (left > 0) {
      const int64_t take = std::min(left, kTrianglesPerFlush - in_run);
      add(first, take, r.mask);
      first += static_cast<uint64_t>(take);
      left -= take;
    }
  }
  if (in_run > 0) flush_ends_.push_back(draw_counts_.size());
}

absl::Status OsMesaShadowMapRenderer::Render(const ShadowMapCamera& camera,
                                             std::vector<float>* depth) {
  const DrawRange all{0, static_cast<uint32_t>(index_count_ / 3)};
  return Render(camera, std::span<const DrawRange>(&all, 1), depth);
}

absl::Status OsMesaShadowMapRenderer::Render(const ShadowMapCamera& camera,
                                             std::span<const DrawRange> ranges,
                                             std::vector<float>* depth) {
  for (const DrawRange& r : ranges) {
    if (uint64_t{r.first_triangle} + r.triangle_count > static_cast<uint64_t>(index_count_ / 3)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("draw range [%d, %d) past the %d uploaded triangles", r.first_triangle,
                          uint64_t{r.first_triangle} + r.triangle_count, index_count_ / 3));
    }
    if (r.mask > mask_textures_.size()) {
      return absl::InvalidArgumentError(
          absl::StrFormat("draw range at %d: mask %d past the %d masks set", r.first_triangle,
                          r.mask, mask_textures_.size()));
    }
    if (r.mask != 0 && !has_uvs_) {
      return absl::InvalidArgumentError(
          absl::StrFormat("draw range at %d: alpha-tested (mask %d) but no UVs were uploaded",
                          r.first_triangle, r.mask));
    }
  }
  SetDrawList(ranges);
  if (absl::Status status = ValidateCamera(camera); !status.ok()) return status;
  const ShadowMapWindow& window = camera.window;
  depth->assign(static_cast<size_t>(window.width) * window.height,
                std::numeric_limits<float>::infinity());
  if (depth->empty()) return absl::OkStatus();
  if (absl::Status status = context_.MakeCurrent(); !status.ok()) return status;
  SetPipelineState(camera);
  // Pieces are sub-windows of the same lattice, each with its own matrix.
  for (int py = 0; py < window.height; py += max_piece_size_) {
    for (int px = 0; px < window.width; px += max_piece_size_) {
      const ShadowMapWindow piece{window.x0 + px, window.y0 + py,
                                  std::min(max_piece_size_, window.width - px),
                                  std::min(max_piece_size_, window.height - py)};
      float* out = depth->data() + static_cast<size_t>(py) * window.width + px;
      if (absl::Status status = RenderPiece(camera, piece, window.width, out); !status.ok()) {
        return status;
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace

std::array<float, 16> ShadowMapClipFromLight(const ShadowMapCamera& camera,
                                             const ShadowMapWindow& piece, bool zero_to_one_clip) {
  const ShadowMapLattice& lattice = camera.lattice;
  const double s_lo = lattice.EdgeS(piece.x0), s_hi = lattice.EdgeS(piece.x0 + piece.width);
  const double t_lo = lattice.EdgeT(piece.y0), t_hi = lattice.EdgeT(piece.y0 + piece.height);
  const double sc = 0.5 * (s_lo + s_hi), hs = 0.5 * (s_hi - s_lo);
  const double tc = 0.5 * (t_lo + t_hi), ht = 0.5 * (t_hi - t_lo);
  const double a = camera.sample.x, b = camera.sample.y;
  double rows[4][4];
  if (camera.projection == Projection::kPerspective) {
    const double n = camera.z_clip_near;
    // clang-format off
    const double r[4][4] = {{1 / hs, 0, -sc / hs, -a / hs},
                            {0, 1 / ht, -tc / ht, -b / ht},
                            {0, 0, 0, n},
                            {0, 0, 1, 0}};
    // clang-format on
    std::copy(&r[0][0], &r[0][0] + 16, &rows[0][0]);
  } else {
    const double range = camera.z_clip_far - camera.z_clip_near;
    double z_row[4] = {0, 0, -1 / range, camera.z_clip_far / range};
    if (!zero_to_one_clip) {
      z_row[2] *= 2;
      z_row[3] = 2 * z_row[3] - 1;
    }
    // clang-format off
    const double r[4][4] = {{1 / hs, 0, -a / hs, -sc / hs},
                            {0, 1 / ht, -b / ht, -tc / ht},
                            {z_row[0], z_row[1], z_row[2], z_row[3]},
                            {0, 0, 0, 1}};
    // clang-format on
    std::copy(&r[0][0], &r[0][0] + 16, &rows[0][0]);
  }
  std::array<float, 16> column_major;
  for (int col = 0; col < 4; ++col) {
    for (int row = 0; row < 4; ++row) {
      column_major[col * 4 + row] = static_cast<float>(rows[row][col]);
    }
  }
  return column_major;
}

absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> ShadowMapRenderer::Create() {
  return Create(Options{});
}

absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> ShadowMapRenderer::Create(
    const Options& options) {
  absl::StatusOr<gl::OsMesaContext> context = gl::OsMesaContext::Create();
  if (!context.ok()) return context.status();
  absl::StatusOr<GlFunctions> gl = GlFunctions::Load(&gl::OsMesaContext::GetProcAddress);
  if (!gl.ok()) return gl.status();
  auto renderer = std::make_unique<OsMesaShadowMapRenderer>(*std::move(context), *gl);
  if (absl::Status status = renderer->Init(options); !status.ok()) return status;
  return renderer;
}

}  // namespace pdsm
