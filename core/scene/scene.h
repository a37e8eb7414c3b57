// The validated, in-memory scene a bake works on: world-space triangles in double precision,
// the lights with their frames, and each light's bake settings with every default filled in.
#ifndef PDSM_CORE_SCENE_SCENE_H_
#define PDSM_CORE_SCENE_SCENE_H_

#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"

#include "core/geometry/light_frame.h"
#include "core/scene/alpha_mask.h"

namespace pdsm {

enum class MeshRole { kCasterAndReceiver, kCasterOnly, kReceiverOnly };

inline bool Casts(MeshRole role) { return role != MeshRole::kReceiverOnly; }
inline bool Receives(MeshRole role) { return role != MeshRole::kCasterOnly; }

struct TriangleMesh {
  std::string label;  // "meshes[2] (models/dragon.ply)", for messages
  // The scene file's meshes[] entry it comes from. A file whose nodes set roles
  // (core/scene/node_roles.h) gives one TriangleMesh per role, all of the same entry.
  int entry = 0;
  MeshRole role = MeshRole::kCasterAndReceiver;
  // Adaptive resolution may refine the shadows on its surfaces (the entry's `refine`).
  bool refine = true;
  std::vector<glm::dvec3> positions_world;  // transformed, double
  std::vector<uint32_t> indices;            // 3 per triangle
  // Alpha-tested triangles, as MeshFileData holds them (core/scene/mesh_file.h): all empty
  // for an opaque mesh; else a UV per vertex and a mask index per triangle (0 opaque, k:
  // masks[k - 1]). Only casting is tested; a receiver's surface is its whole triangles.
  std::vector<glm::vec2> uvs;
  std::vector<uint16_t> triangle_masks;
  std::vector<std::shared_ptr<const AlphaMask>> masks;
  bool has_masks() const { return !masks.empty(); }
};

enum class LightShape { kRect, kDisk, kSun };

// "rect", "disk", "sun": the scene file's names, for messages and `pdsm info`.
inline const char* LightShapeName(LightShape shape) {
  switch (shape) {
    case LightShape::kRect:
      return "rect";
    case LightShape::kDisk:
      return "disk";
    case LightShape::kSun:
      return "sun";
  }
  return "?";
}

struct LightSpec {
  LightShape shape = LightShape::kRect;
  // Rect and disk: the light's own frame (centre on the light, n into the scene).
  // Sun: only the axes are meaningful here; the bake plan chooses the centre.
  LightFrame frame;
  double half_width = 0;      // rect, along u, world units
  double half_height = 0;     // rect, along v, world units
  double radius = 0;          // disk, world units
  double tan_half_angle = 0;  // sun: tan(angular diameter / 2)
  // A spot light: a disk (shape kDisk, `radius`) whose PDSM covers only its cone, |s|, |t| <=
  // tan(cone half-angle). 0: no cone (every other light).
  double cone_half_angle_deg = 0;
  bool is_spot() const { return cone_half_angle_deg > 0; }
  // A face of a sphere light (core/scene/sphere_faces.h): a disk (shape kDisk, the sphere's
  // `radius`, centred on the sphere) whose PDSM covers only the face's directions, |s|, |t| <=
  // face_tangent. 0: not a face (every other light).
  double face_tangent = 0;
  bool is_sphere_face() const { return face_tangent > 0; }
};

enum class SamplingPattern { kStratified, kUniform, kSobol, kHalton, kBlueNoise };
enum class CompressionMetric { kVertical, kPerpendicular };
// What each light sample counts for at a point (core/reference/light_weighting.h): a bake
// takes kUnweighted or kEmitter (core/events/emitter_weighting.h); kIrradiance needs the
// receiver's normal and exists only in the references.
enum class LightWeighting { kUnweighted, kEmitter, kIrradiance };

struct FrustumOverride {
  double s_min, s_max, t_min, t_max;
  double z_near, z_far;
};

// Documented in docs/scene_format.md; ValidateBakeSettings enforces the limits.
struct BakeSettings {
  int width = 512;
  int height = 512;
  int samples = 64;
  int shadow_map_resolution = 512;
  double epsilon = 0.01;
  std::optional<double> depth_bias;  // unset: derived from the scene size by the plan
  double slope_bias = 1.0;
  int tile_size = 64;
  uint64_t seed = 1;
  SamplingPattern sampling = SamplingPattern::kSobol;  // the measured best (docs/accuracy.md)
  CompressionMetric compression_metric = CompressionMetric::kVertical;
  LightWeighting weighting = LightWeighting::kUnweighted;  // kUnweighted or kEmitter
  std::optional<FrustumOverride> frustum;
  // Adaptive sampling: 0 is off (every tile uses `samples`); > 0 lets a tile stop once its
  // estimated error is at most this, `samples` being the maximum (docs/algorithms.md).
  double adaptive_tolerance = 0;
  int adaptive_min_samples = 16;
  bool adaptive() const { return adaptive_tolerance > 0; }
  // Keep each ray's function only near the receiver surfaces it can be queried at
  // (docs/algorithms.md, "Surfaces only"); free-space queries are then undefined (NaN).
  bool surfaces_only = false;
  // Tiles per side of a tile group; 0: chosen by the plan (core/bake/tile_groups.h).
  int tile_group_size = 0;
  // Adaptive resolution: the largest refinement per axis of a pixel whose penumbra is narrower
  // than it, 1 (off), 2, 4 or 8 (docs/algorithms.md "Adaptive resolution").
  int max_refinement = 1;
};

// One light of a scene with the settings it bakes with.
struct SceneLight {
  std::string name;  // empty only for a one-light scene's light that was given no name
  LightSpec spec;
  BakeSettings bake;  // the scene's `bake`, then the light's own, then any overrides
};

// A bake plans one light at a time (core/bake/bake_plan.h): `light`, `bake` and `light_name`
// are the light this Scene bakes, the scene file's first one. A file's further lights wait in
// `more_lights`; ForLight gives the Scene that bakes any one of them.
struct Scene {
  std::string name;
  std::string source_path;  // the scene file, for messages
  std::vector<TriangleMesh> meshes;
  LightSpec light;
  BakeSettings bake;
  std::string light_name;               // "" for an unnamed single light
  std::vector<SceneLight> more_lights;  // the file's lights after the first, in order

  size_t LightCount() const { return 1 + more_lights.size(); }
};

// The i-th light of `scene` (0: the first, held in light/bake/light_name). REQUIRES:
// i < scene.LightCount().
SceneLight LightOf(const Scene& scene, size_t i);

// `scene` baking its i-th light: that light in light/bake/light_name, no further lights, the
// same meshes (copied). REQUIRES: i < scene.LightCount().
Scene ForLight(const Scene& scene, size_t i);

// The index of the light named `name`, or -1.
int FindLight(const Scene& scene, std::string_view name);

// For the commands that work on one light (`what`: "pdsm reference"): `scene` baking the light
// named `light`, or its only light when `light` is empty. A sphere light, named or the only
// light, is its first face (core/scene/sphere_faces.h), as are its faces named one by one.
// INVALID_ARGUMENT naming the scene file and its lights when `light` names none of them, or is
// empty and there are several; `flag`, when the command has one ("--light"), is named as the way to
// choose.
absl::StatusOr<Scene> OneLight(Scene scene, std::string_view light, std::string_view what,
                               std::string_view flag = {});

// Limits on user input (docs/scene_format.md). Larger requests are refused, not clamped.
// A map's side, its pixels (2^30: a 32768^2 map; pixel indices stay within 32-bit ints) and
// its tiles (2^20: a 65536-pixel-wide map of 64-pixel tiles has 1024 a row; each tile costs a
// few dozen bytes in plans, job stores and the file's offset table).
inline constexpr int kMaxPdsmResolution = 65536;
inline constexpr int64_t kMaxPdsmPixels = int64_t{1} << 30;
inline constexpr int64_t kMaxPdsmTiles = int64_t{1} << 20;
inline constexpr int kMaxSamples = 65536;
inline constexpr int kMaxShadowMapResolution = 16384;
inline constexpr int kMaxTileSize = 4096;
// A scene's `name`: a label for headers, listings and logs, not a payload (a 5 MiB name made
// one job listing exceed a client's 4 MiB message limit).
inline constexpr size_t kMaxSceneNameBytes = 256;
// Lights of one scene (one PDSM file part each), and the length of a light's name.
inline constexpr int kMaxLights = 16384;
inline constexpr size_t kMaxLightNameBytes = 64;
// A spot's cone: a perspective PDSM covers at most 85 degrees off its axis (bake_plan.h).
inline constexpr double kMaxConeHalfAngleDeg = 85;

}  // namespace pdsm

#endif  // PDSM_CORE_SCENE_SCENE_H_
