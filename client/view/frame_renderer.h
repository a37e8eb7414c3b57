// Draws one frame of a ViewScene in one mode into an offscreen target: colour (RGBA8) and the
// attenuation each pixel was shaded with (R32F), both readable back; a window blits the colour
// to the screen. The GL context is the caller's (OSMesa headless, GLFW in a window); it must
// be current on this thread for every call and outlive the renderer.
#ifndef PDSM_CLIENT_VIEW_FRAME_RENDERER_H_
#define PDSM_CLIENT_VIEW_FRAME_RENDERER_H_

#include <cstdint>
#include <memory>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "client/view/camera.h"
#include "client/view/pdsm_tile_pool.h"
#include "client/view/shadow_maps.h"
#include "client/view/view_mode.h"
#include "client/view/view_scene.h"
#include "gl/gl_functions.h"
#include "gl/gl_objects.h"
#include "gl/gl_program.h"

namespace pdsm::view {

// How the PDSM modes combine the baked attenuation A_b with the dynamic objects' own soft
// shadow A_d (docs/viewer.md, "Dynamic objects" has the measurement behind the default).
enum class DynamicCombine {
  kMax = 0,      // max(A_b, A_d): the two hide the same part of the light where they overlap
  kProduct = 1,  // 1 - (1 - A_b)(1 - A_d): they hide independent parts of it
};

struct RenderSettings {
  bool bilinear = true;   // PDSM: blend 4 pixels (thesis 4.2); off: nearest pixel
  int sm_size = 0;        // hard/pcf/pcss/vsm map, texels per side; 0: the bake's
  int sm_count = 0;       // multi-sm maps; 0: the bake's sample count
  int multi_sm_size = 0;  // multi-sm texels per side; 0: the bake's, at most 1024
  int filter_radius = 2;  // pcf and vsm kernel half-width, texels
  float ambient = 0.15f;
  // pdsm and cpu modes: the dynamic objects (not in the bake) cast a real-time soft shadow,
  // the average of `dynamic_sm_count` shadow maps of those objects alone from light samples
  // (Sobol, the bake's seed), combined with the baked attenuation by `dynamic_combine`.
  bool dynamic_shadows = true;
  int dynamic_sm_count = 32;
  int dynamic_sm_size = 512;
  DynamicCombine dynamic_combine = DynamicCombine::kProduct;  // measured best (docs/viewer.md)
  // pdsm and shadowmask modes: the GPU memory the PDSM's resident tiles may take (the tile
  // pool, client/view/pdsm_tile_pool.h); tiles a frame reads past it are drawn not resident.
  int64_t gpu_budget_bytes = kDefaultGpuBudgetBytes;
  int64_t max_pool_buffer_bytes = 0;  // > 0: one pool buffer's cap below the GL's (tests)
};

// Attenuation read back per pixel: the value shaded with, or one of these.
inline constexpr float kOutsidePdsm = -1.0f;  // pdsm/cpu: outside the PDSM frustum (lit)
inline constexpr float kBackground = -2.0f;   // no surface
inline constexpr float kPending = -3.0f;      // pdsm: its PDSM pixels are not baked yet
inline constexpr float kNotResident = -4.0f;  // pdsm: its tiles are over --gpu-budget-mib

struct Frame {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;        // row 0 at the top
  std::vector<float> attenuation;  // row 0 at the top
};

struct FrameTimings {
  double shadow_map_seconds = 0;  // shadow maps rendered for this frame (0 when cached)
  double shade_seconds = 0;       // camera passes, with glFinish
  double cpu_seconds = 0;         // cpu mode: read-back + QueryAttenuation + upload
  double stream_seconds = 0;      // pdsm modes: feedback pass + tiles read and uploaded (0
                                  // when the view did not change)
};

class FrameRenderer {
 public:
  // REQUIRES: a current GL 4.5 core context from the driver `gl` was loaded from; `gl` and
  // `scene` outlive the renderer. Uploads the scene and the PDSM. FAILED_PRECONDITION for an
  // older GL; RESOURCE_EXHAUSTED for a PDSM too large for this GL; INTERNAL for GL failures.
  static absl::StatusOr<std::unique_ptr<FrameRenderer>> Create(const gl::GlFunctions& gl,
                                                               const ViewScene* scene,
                                                               const RenderSettings& settings);
  ~FrameRenderer();
  FrameRenderer(const FrameRenderer&) = delete;
  FrameRenderer& operator=(const FrameRenderer&) = delete;

  // Renders into the offscreen target (resized to width x height).
  absl::Status Render(ViewMode mode, const Camera& camera, int width, int height);
  // The last rendered frame.
  absl::StatusOr<Frame> ReadFrame();
  // Copies the last frame's colour to the default framebuffer (window mode).
  void BlitToScreen(int screen_width, int screen_height);

  // The scene's PDSM (or its pending tiles) changed: a new tile pool, empty.
  absl::Status ReplacePdsm();

  // The dynamic objects moved: shadow maps are re-rendered on the next frame that needs them.
  void InvalidateShadowMaps() {
    streamed_valid_ = false;  // a moved object may show other tiles
    layers_valid_ = false;
    single_valid_ = false;
    dynamic_valid_ = false;
  }

  // The light-space position of the surface each pixel of `camera`'s view shows (x, y, z, 1),
  // or (0, 0, 0, 0) for the background; row 0 at the top, width * height * 4 floats. For
  // measurements against a reference at the very points a frame shaded.
  absl::StatusOr<std::vector<float>> ReadPositions(const Camera& camera, int width, int height);
  RenderSettings& settings() { return settings_; }
  const TilePoolStats& pdsm_pool_stats() const;
  uint64_t shadow_map_bytes() const;
  const FrameTimings& last_timings() const { return timings_; }
  const std::vector<glm::dvec2>& multi_sm_samples() const { return samples_; }
  const std::vector<glm::dvec2>& dynamic_sm_samples() const { return dynamic_samples_; }

 private:
  struct Impl;
  FrameRenderer(const gl::GlFunctions& gl, const ViewScene* scene, const RenderSettings& s);
  absl::Status Init();
  absl::Status EnsureTarget(int width, int height);
  absl::Status EnsureShadowMaps(ViewMode mode);
  absl::Status EnsureDynamicShadowMaps(ViewMode mode);
  void UpdateDynamicReach();
  bool CastsDynamicShadows(ViewMode mode) const;
  absl::Status RenderGbuffer(const glm::mat4& clip_from_light, std::vector<float>* gbuffer);
  absl::Status RenderCpuAttenuation(const glm::mat4& clip_from_light);
  // pdsm modes: the feedback pass (the G-buffer's positions) and the tiles it asks for made
  // resident; skipped while the view and the scene are unchanged.
  absl::Status StreamTiles(const glm::mat4& clip_from_light);
  // What a pass draws: everything, what casts into the comparison modes' maps (baked casters
  // and the dynamic objects), or the dynamic objects alone.
  enum class DrawSet { kAll, kCasters, kDynamic };
  void DrawScene(const gl::UniformSetter& u, DrawSet set) const;
  // Shadowmask mode: the receivers that have a texture, over what DrawScene drew.
  void DrawShadowmasked(const gl::UniformSetter& u) const;
  void SetDepthUniforms(const gl::UniformSetter& u) const;
  void SetShadeUniforms(ViewMode mode, const Camera& camera, const gl::UniformSetter& u) const;

  const gl::GlFunctions& gl_;
  const ViewScene* scene_;
  RenderSettings settings_;
  std::unique_ptr<Impl> impl_;
  bool single_valid_ = false;    // the centre shadow map (hard, pcf, pcss, vsm)
  bool layers_valid_ = false;    // the multi-sm maps
  bool dynamic_valid_ = false;   // the dynamic objects' maps
  bool streamed_valid_ = false;  // the tiles of the view below are resident (as far as fit)
  glm::mat4 streamed_clip_{0.0f};
  int streamed_width_ = 0, streamed_height_ = 0;
  std::vector<glm::dvec2> samples_;
  std::vector<glm::dvec2> dynamic_samples_;
  // Window coordinates where the dynamic maps hold an object, over every sample (grown by a
  // texel): a fragment looking up none of them has none of its shadow, and skips the maps.
  // Unbounded when an object reaches behind a perspective light.
  bool dynamic_reach_bounded_ = false;
  glm::dvec2 dynamic_reach_min_{0.0}, dynamic_reach_max_{0.0};
  glm::dvec2 dynamic_sample_min_{0.0}, dynamic_sample_max_{0.0};
  FrameTimings timings_;
};

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_FRAME_RENDERER_H_
