// Shadow maps for the comparison modes, rendered with the PDSM's own orientation (parallel
// shadow maps, as the bake renders them, DESIGN.md "Geometry of the bake"): a light-space
// point (x, y, z) lands at ((x - a) / z, (y - b) / z) for the light sample at (a, b, 0), or at
// (x - a z, y - b z) for a sun sample direction (a, b, 1).
//
// hard, pcf, pcss and vsm use one map from the light centre (RG32F: biased depth, second
// moment); multi-sm renders one R32F layer per light sample of the bake, the brute force a
// PDSM replaces, and the PDSM modes a few layers of the dynamic objects alone (their real-time
// soft shadow). All are drawn with the bake's depth bias and slope bias (PDSM header).
#ifndef PDSM_CLIENT_VIEW_SHADOW_MAPS_H_
#define PDSM_CLIENT_VIEW_SHADOW_MAPS_H_

#include <functional>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"

namespace pdsm::view {

// The window (light-space s, t) a set of shadow maps covers, and their texels per side.
struct ShadowMapLayout {
  glm::dvec2 window_min{0.0};
  glm::dvec2 window_size{1.0};
  int size = 0;
};

// Half extents of the light as the shaders use them: rect (w/2, h/2), disk (r, r), light-space
// units; sun (tan, tan) of the half angle.
glm::dvec2 LightHalfExtent(const PdsmHeader& header);

// The PDSM's window; with `grow_for_samples`, widened by what a sample at the light's edge
// shifts a receiver (perspective: extent / z_near; sun: extent * z_far), at most doubled.
ShadowMapLayout MakeShadowMapLayout(const PdsmHeader& header, int size, bool grow_for_samples);

// clip_from_light of the shadow map of the sample `sample` (see above), with clip z / w in
// [0, 1] (glClipControl GL_ZERO_TO_ONE) nearer larger, wide enough in depth not to clip
// dynamic objects a little in front of the bake's z_near.
// Depth range of the shadow maps' clip space, light-space z: wider than the bake's so that a
// dynamic object moved past z_near or z_far still casts (it is only clipped at the light).
struct ShadowClipRange {
  double near, far;
};
ShadowClipRange ShadowClipRangeOf(const PdsmGeometry& g);

glm::mat4 ShadowClipFromLight(const PdsmHeader& header, const ShadowMapLayout& layout,
                              glm::dvec2 sample);

// Owns the shadow maps' render targets and sets the pipeline state for them; the caller's
// draw callback sets its clip matrix and issues the draws with the shadow-depth program.
class ShadowMapTargets {
 public:
  explicit ShadowMapTargets(const gl::GlFunctions& gl) : gl_(&gl) {}

  // `draw(clip_from_light)` draws the casters with the shadow-depth program in use.
  using DrawFn = std::function<void(const glm::mat4& clip_from_light)>;

  // Renders the centre map into `single()` (resized to layout.size).
  absl::Status RenderSingle(const PdsmHeader& header, const ShadowMapLayout& layout,
                            const DrawFn& draw);
  // Renders one layer per sample into `layers()`. RESOURCE_EXHAUSTED beyond the layer limit
  // or 2 GiB of maps.
  absl::Status RenderLayers(const PdsmHeader& header, const ShadowMapLayout& layout,
                            const std::vector<glm::dvec2>& samples, const DrawFn& draw);

  GLuint single() const { return single_.name(); }
  GLuint layers() const { return layers_.name(); }
  uint64_t bytes() const { return bytes_single_ + bytes_layers_; }

 private:
  absl::Status Bind(GLuint colour, int layer, int size);
  void Clear(const PdsmHeader& header, bool layered);

  const gl::GlFunctions* gl_;
  gl::Framebuffer framebuffer_;
  gl::Texture depth_;  // DEPTH_COMPONENT32F, reversed
  int depth_size_ = 0;
  gl::Texture single_;  // RG32F
  int single_size_ = 0;
  gl::Texture layers_;  // R32F array
  int layers_size_ = 0, layer_count_ = 0;
  uint64_t bytes_single_ = 0, bytes_layers_ = 0;
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_SHADOW_MAPS_H_
