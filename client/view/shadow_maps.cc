#include "client/view/shadow_maps.h"

#include <algorithm>
#include <limits>

#include "absl/strings/str_cat.h"
#include "gl/gl_program.h"

namespace pdsm::view {
namespace {

constexpr uint64_t kMaxLayerBytes = uint64_t{2} << 30;

}  // namespace

ShadowClipRange ShadowClipRangeOf(const PdsmGeometry& g) {
  const double range = std::max(g.z_far - g.z_near, 1e-6);
  return {g.projection == Projection::kPerspective ? 0.25 * g.z_near : g.z_near - range,
          g.z_far + range};
}

glm::dvec2 LightHalfExtent(const PdsmHeader& header) {
  switch (header.light_shape) {
    case LightShape::kRect:
      return {header.light_half_width, header.light_half_height};
    case LightShape::kDisk:
      return {header.light_radius, header.light_radius};
    case LightShape::kSun:
      return {header.tan_half_angle, header.tan_half_angle};
  }
  return {0, 0};
}

ShadowMapLayout MakeShadowMapLayout(const PdsmHeader& header, int size, bool grow_for_samples) {
  const PdsmGeometry& g = header.geometry;
  ShadowMapLayout layout;
  layout.size = size;
  layout.window_min = {g.s_min, g.t_min};
  layout.window_size = {g.s_max - g.s_min, g.t_max - g.t_min};
  if (grow_for_samples) {
    const glm::dvec2 extent = LightHalfExtent(header);
    glm::dvec2 margin = g.projection == Projection::kPerspective
                            ? extent / std::max(g.z_near, 1e-9)
                            : extent * std::max(std::abs(g.z_far), std::abs(g.z_near));
    margin = glm::min(margin, 0.5 * layout.window_size);
    layout.window_min -= margin;
    layout.window_size += 2.0 * margin;
  }
  return layout;
}

glm::mat4 ShadowClipFromLight(const PdsmHeader& header, const ShadowMapLayout& layout,
                              glm::dvec2 sample) {
  const PdsmGeometry& g = header.geometry;
  const glm::dvec2 half = 0.5 * layout.window_size;
  const glm::dvec2 centre = layout.window_min + half;
  const ShadowClipRange clip = ShadowClipRangeOf(g);
  const double a = sample.x, b = sample.y;
  glm::dmat4 m(0.0);  // m[col][row]
  if (g.projection == Projection::kPerspective) {
    // x_clip = (x - a - sc z) / hs, w = z  =>  x_ndc = ((x - a) / z - sc) / hs; z_ndc = n / z.
    m[0][0] = 1 / half.x;
    m[2][0] = -centre.x / half.x;
    m[3][0] = -a / half.x;
    m[1][1] = 1 / half.y;
    m[2][1] = -centre.y / half.y;
    m[3][1] = -b / half.y;
    m[3][2] = clip.near;
    m[2][3] = 1;
  } else {
    // x_ndc = (x - a z - sc) / hs; z_ndc = (far - z) / (far - near).
    const double range = clip.far - clip.near;
    m[0][0] = 1 / half.x;
    m[2][0] = -a / half.x;
    m[3][0] = -centre.x / half.x;
    m[1][1] = 1 / half.y;
    m[2][1] = -b / half.y;
    m[3][1] = -centre.y / half.y;
    m[2][2] = -1 / range;
    m[3][2] = clip.far / range;
    m[3][3] = 1;
  }
  return glm::mat4(m);
}

absl::Status ShadowMapTargets::Bind(GLuint colour, int layer, int size) {
  const gl::GlFunctions& gl = *gl_;
  if (!framebuffer_) framebuffer_ = gl::MakeFramebuffer(gl);
  if (depth_size_ != size) {
    depth_ = gl::MakeTexture(gl);
    gl.BindTexture(GL_TEXTURE_2D, depth_.name());
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_DEPTH_COMPONENT32F, size, size, 0, GL_DEPTH_COMPONENT,
                  GL_FLOAT, nullptr);
    depth_size_ = size;
  }
  gl.BindFramebuffer(GL_FRAMEBUFFER, framebuffer_.name());
  if (layer < 0) {
    gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, colour, 0);
  } else {
    gl.FramebufferTextureLayer(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, colour, 0, layer);
  }
  gl.FramebufferTexture2D(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_TEXTURE_2D, depth_.name(), 0);
  const GLenum draw_buffer = GL_COLOR_ATTACHMENT0;
  gl.DrawBuffers(1, &draw_buffer);
  const GLenum status = gl.CheckFramebufferStatus(GL_FRAMEBUFFER);
  if (status != GL_FRAMEBUFFER_COMPLETE) {
    return absl::InternalError(absl::StrCat("shadow-map framebuffer incomplete: ", status));
  }
  gl.Viewport(0, 0, size, size);
  gl.ClipControl(GL_LOWER_LEFT, GL_ZERO_TO_ONE);
  gl.Enable(GL_DEPTH_TEST);
  gl.DepthFunc(GL_GREATER);  // reversed depth: nearer is larger
  gl.DepthMask(GL_TRUE);
  gl.Disable(GL_CULL_FACE);  // both sides of a caster cast
  gl.Disable(GL_SCISSOR_TEST);
  return absl::OkStatus();
}

absl::Status ShadowMapTargets::RenderSingle(const PdsmHeader& header, const ShadowMapLayout& layout,
                                            const DrawFn& draw) {
  const gl::GlFunctions& gl = *gl_;
  if (single_size_ != layout.size) {
    single_ = gl::MakeTexture(gl);
    gl.BindTexture(GL_TEXTURE_2D, single_.name());
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl.TexImage2D(GL_TEXTURE_2D, 0, GL_RG32F, layout.size, layout.size, 0, GL_RG, GL_FLOAT,
                  nullptr);
    single_size_ = layout.size;
    bytes_single_ = uint64_t{8} * layout.size * layout.size;
  }
  if (absl::Status s = Bind(single_.name(), -1, layout.size); !s.ok()) return s;
  Clear(header, /*layered=*/false);
  draw(ShadowClipFromLight(header, layout, glm::dvec2(0.0)));
  return gl::CheckGlError(gl, "rendering the shadow map");
}

absl::Status ShadowMapTargets::RenderLayers(const PdsmHeader& header, const ShadowMapLayout& layout,
                                            const std::vector<glm::dvec2>& samples,
                                            const DrawFn& draw) {
  const gl::GlFunctions& gl = *gl_;
  const int count = static_cast<int>(samples.size());
  GLint max_layers = 0;
  gl.GetIntegerv(GL_MAX_ARRAY_TEXTURE_LAYERS, &max_layers);
  const uint64_t bytes = uint64_t{4} * layout.size * layout.size * count;
  if (count > max_layers || bytes > kMaxLayerBytes) {
    return absl::ResourceExhaustedError(
        absl::StrCat(count, " shadow maps of ", layout.size, "^2 (", bytes >> 20, " MiB; at most ",
                     max_layers, " layers and ", kMaxLayerBytes >> 20,
                     " MiB here): lower the map count or size (--sm-count, --multi-sm-size, "
                     "--dynamic-sm-count, --dynamic-sm-size)"));
  }
  if (layers_size_ != layout.size || layer_count_ != count) {
    layers_ = gl::MakeTexture(gl);
    gl.BindTexture(GL_TEXTURE_2D_ARRAY, layers_.name());
    gl.TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    gl.TexParameteri(GL_TEXTURE_2D_ARRAY, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    gl.TexImage3D(GL_TEXTURE_2D_ARRAY, 0, GL_R32F, layout.size, layout.size, std::max(count, 1), 0,
                  GL_RED, GL_FLOAT, nullptr);
    layers_size_ = layout.size;
    layer_count_ = count;
    bytes_layers_ = bytes;
  }
  for (int k = 0; k < count; ++k) {
    if (absl::Status s = Bind(layers_.name(), k, layout.size); !s.ok()) return s;
    Clear(header, /*layered=*/true);
    draw(ShadowClipFromLight(header, layout, samples[k]));
  }
  return gl::CheckGlError(gl, "rendering the layered shadow maps");
}

void ShadowMapTargets::Clear(const PdsmHeader& header, bool layered) {
  // "No caster": the single map (VSM's moments) a depth beyond every receiver (z_far + range,
  // normalised depth 2), finite so that filtered moments stay meaningful next to a silhouette;
  // the layers (plain depth tests) +infinity, so that a dynamic object moved farther than that
  // is not taken for shadowed.
  const PdsmGeometry& g = header.geometry;
  const double range = std::max(g.z_far - g.z_near, 1e-6);
  const float no_caster[4] = {
      layered ? std::numeric_limits<float>::infinity() : static_cast<float>(g.z_far + range), 4.0f,
      0, 0};
  const float beyond_everything = 0.0f;
  gl_->ClearBufferfv(GL_COLOR, 0, no_caster);
  gl_->ClearBufferfv(GL_DEPTH, 0, &beyond_everything);
}

}  // namespace pdsm::view
