// Renders one parallel shadow map (DESIGN.md "Geometry of the bake") with OSMesa, headless:
// the shadow map of light sample k has the PDSM's orientation, so a light-space point
// (x, y, z) lands at ((x - a) / z, (y - b) / z) (perspective, sample at (a, b, 0)) or at
// (x - a z, y - b z) (sun, sample direction (a, b, 1)), and its depth is the same light-space
// z as the PDSM's. Each texel stores the biased light-space depth of the nearest caster, or
// +infinity where there is none.
#ifndef PDSM_WORKER_SHADOW_MAP_RENDERER_H_
#define PDSM_WORKER_SHADOW_MAP_RENDERER_H_

#include <array>
#include <cstdint>
#include <glm/glm.hpp>
#include <memory>
#include <span>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/bake/shadow_map_lattice.h"
#include "core/pdsm/pdsm_geometry.h"
#include "core/scene/alpha_mask.h"

namespace pdsm {

// Triangles [first_triangle, first_triangle + triangle_count) of the uploaded geometry.
struct DrawRange {
  uint32_t first_triangle = 0;
  uint32_t triangle_count = 0;
  // 0: opaque; k: alpha-tested by the k-th mask given to SetMasks (core/scene/alpha_mask.h).
  uint16_t mask = 0;
};

struct ShadowMapCamera {
  Projection projection = Projection::kPerspective;
  glm::dvec2 sample{0.0};  // perspective: (a, b) on the light plane; sun: direction slopes
  ShadowMapLattice lattice;
  ShadowMapWindow window;  // the texels to render
  double z_clip_near = 0;  // light-space depth; nearer geometry is clipped
  double z_clip_far = 0;   // sun only: farther geometry is clipped
  // Bias (one function: BiasedDepth, shaders/common/shadow_bias.glsl): stored depth =
  //   z + depth_bias + slope_bias * footprint_scale * (|dz/dx| + |dz/dy|) per texel.
  double depth_bias = 0;
  double slope_bias = 0;
  double footprint_scale = 1;
};

// The shadow-map program's clip_from_light (column-major) for the texels `piece` of
// `camera.lattice`: NDC x, y span the piece's edges exactly; clip z / w is the reversed depth
// (DESIGN.md). Computed in double, rounded once to float. `zero_to_one_clip`: glClipControl
// (GL_ZERO_TO_ONE) is in effect; otherwise clip z is remapped to [-1, 1] (only the
// orthographic depth needs it: the perspective near-plane test -w <= n <= w equals
// 0 <= n <= w for n > 0). Public so that bench/layered_maps.cc draws the same maps another way.
std::array<float, 16> ShadowMapClipFromLight(const ShadowMapCamera& camera,
                                             const ShadowMapWindow& piece, bool zero_to_one_clip);

// Owns an OSMesa core-profile context and the GL objects made in it. Not thread-safe: one
// thread at a time. Each call makes the context current on its thread, so a renderer may pass
// to another thread once the thread that used it last has called LeaveThread() (making one
// costs ~20 ms of shader compilation, worth keeping across the lights of a bake). Move-only.
class ShadowMapRenderer {
 public:
  struct Options {
    // Largest piece, in texels per side, that one draw renders; larger windows are split.
    // 0: the GL limits (GL_MAX_TEXTURE_SIZE, GL_MAX_VIEWPORT_DIMS), at most 8192. Odd values
    // are rounded down to even (pieces keep 2x2 derivative quads aligned with the window).
    // Tests set it small to exercise the splitting.
    int max_piece_size = 0;
  };

  // Creates the OSMesa context, current on the calling thread from then on, and the program.
  // INTERNAL when OSMesa or GL fails; INVALID_ARGUMENT for bad options.
  static absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> Create();
  static absl::StatusOr<std::unique_ptr<ShadowMapRenderer>> Create(const Options& options);
  virtual ~ShadowMapRenderer() = default;

  // Uploads the casters, light-space positions relative to the light centre (float is
  // enough there), as triangles (3 indices each). Replaces the previous geometry; empty is
  // fine. INVALID_ARGUMENT (geometry unchanged) for an index out of range, a count not a
  // multiple of 3, or a non-finite position.
  absl::Status SetGeometry(std::span<const glm::vec3> positions_light,
                           std::span<const uint32_t> indices) {
    return SetGeometry(positions_light, indices, {});
  }
  // The same with a UV per vertex (empty, or one per position, finite) for alpha-tested ranges.
  // INVALID_ARGUMENT also for a UV count that is neither.
  virtual absl::Status SetGeometry(std::span<const glm::vec3> positions_light,
                                   std::span<const uint32_t> indices,
                                   std::span<const glm::vec2> uvs) = 0;

  // Uploads the alpha masks DrawRange::mask names (k: masks[k - 1]), replacing the previous
  // ones; the first non-empty call compiles the alpha-tested program. Each mask must be Valid()
  // (INVALID_ARGUMENT otherwise); INTERNAL when GL fails (out of memory: RESOURCE_EXHAUSTED).
  virtual absl::Status SetMasks(std::span<const std::shared_ptr<const AlphaMask>> masks) = 0;

  // Renders `camera.window` into `depth` (resized to width * height, row-major, row 0 at the
  // window's lowest t). Windows larger than the GL limits are rendered in pieces. Output is
  // bit-identical for the same camera and geometry, whatever was rendered before. INVALID_ARGUMENT
  // for a bad camera (perspective needs z_clip_near > 0; orthographic z_clip_far >
  // z_clip_near; pitches > 0); INTERNAL when GL fails.
  virtual absl::Status Render(const ShadowMapCamera& camera, std::vector<float>* depth) = 0;

  // The same, drawing only the triangles of `ranges` (in order; ranges may be adjacent, not
  // overlapping). Texels no drawn triangle covers hold +infinity. An alpha-tested range covers
  // only where its mask passes (shaders/shadow_map.frag). INVALID_ARGUMENT for a range past the
  // uploaded triangles, a mask past those set, or a masked range without uploaded UVs.
  virtual absl::Status Render(const ShadowMapCamera& camera, std::span<const DrawRange> ranges,
                              std::vector<float>* depth) = 0;

  // Unbinds the context from the calling thread, so that another thread may use the renderer
  // next. Call on the thread that used it last; the next call binds it again.
  virtual void LeaveThread() = 0;
};

}  // namespace pdsm

#endif  // PDSM_WORKER_SHADOW_MAP_RENDERER_H_
