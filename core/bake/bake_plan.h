// The bake plan: everything fixed before any shadow map is rendered. The PDSM frustum fitted
// to the scene, the global shadow-map lattice, the light samples, the tile grid, and the
// scene's triangles in light space. A plan depends only on the scene, so every process of a
// distributed bake computes the same plan.
#ifndef PDSM_CORE_BAKE_BAKE_PLAN_H_
#define PDSM_CORE_BAKE_BAKE_PLAN_H_

#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/bake/caster_clusters.h"
#include "core/bake/scene_index.h"
#include "core/bake/shadow_map_lattice.h"
#include "core/bake/tile_groups.h"
#include "core/pdsm/pdsm_image.h"
#include "core/scene/scene.h"

namespace pdsm {

class RefinedPixels;  // core/bake/refined_pixels.h

struct TileRect {
  int index = 0;
  int x0 = 0, y0 = 0, width = 0, height = 0;  // PDSM pixels
};

// Triangles in light space, relative to the light centre: small numbers, so float suffices
// for rendering even when the world sits 1e6 units from its origin.
struct LightSpaceMesh {
  std::vector<glm::vec3> positions;
  std::vector<uint32_t> indices;
  // Alpha-tested casters (core/scene/alpha_mask.h): empty when every triangle is opaque; else a
  // UV per vertex and, per triangle, 0 (opaque) or k (tested by the plan's masks[k - 1]).
  std::vector<glm::vec2> uvs;
  std::vector<uint16_t> triangle_masks;
  size_t TriangleCount() const { return indices.size() / 3; }
  uint16_t MaskOf(size_t triangle) const {
    return triangle_masks.empty() ? 0 : triangle_masks[triangle];
  }
};

struct BakePlan {
  PdsmHeader header;                // geometry and knobs, as the file will store them
  std::vector<glm::dvec2> samples;  // see core/sampling/light_samples.h
  ShadowMapLattice lattice;
  double z_clip_near = 0;  // shadow maps clip geometry nearer than this
  double z_clip_far = 0;   // sun shadow maps clip geometry farther than this
  // Perspective rays are scanned from no nearer than this (ScanFloor in bake_plan.cc: where a
  // tile's shadow map reaches kShadowMapTexelBudget, or a ray kMaxRayTexels); 0 for the sun.
  double z_scan_floor = 0;
  // The tiles: a row-major grid of header.tile_size (edge tiles cut), made on demand by tile()
  // so that a plan holds nothing per tile but a bit (a coordinator keeps the plan of every
  // job it runs: core/bake/plan_memory.h).
  int tiles_x = 0, tiles_y = 0;
  // The tile groups, the unit of rendering and of tasks (tile_groups.h): squares of
  // group_side x group_side tiles of the grid, row-major (edge groups cut), made by group().
  int group_side = 1;
  // Per tile: may a caster shadow it (TilesCastersMayReach)? The others are all lit and get
  // no task at all.
  std::vector<bool> tile_has_casters;
  int tile_group_size = 0;  // the scene's bake.tileGroupSize (0: chosen by GroupSideInTiles)
  // The casters some tile can reach (core/bake/caster_culling.h), in the scene index's spatial
  // order, in caster_clusters; casters_left_out more of the scene's are out of every tile's
  // reach.
  LightSpaceMesh casters;
  std::vector<CasterCluster> caster_clusters;
  size_t casters_left_out = 0;
  // The masks casters.triangle_masks index (1-based), shared with the scene: empty when every
  // caster is opaque.
  std::vector<std::shared_ptr<const AlphaMask>> masks;
  // Every receiver, for a surfaces-only plan (its depth windows); empty otherwise unless
  // AddLightSpaceReceivers was called (the light-view preview draws them).
  LightSpaceMesh receivers;
  // A refined plan (header.max_refinement > 1) some of whose receiving meshes opt out of
  // refinement (`refine: false`): true, and refinable_receivers the others, in scene order.
  // Otherwise false and empty: every receiver may be refined. RefinableReceivers() is what
  // choosing the refined pixels reads (core/bake/refinement_selection.h).
  bool some_receivers_unrefined = false;
  LightSpaceMesh refinable_receivers;
  // A refinement level's plan (PlanRefinementLevel): its factor, and the base map's refined
  // pixels, whose sub-pixels are its only rays (core/bake/scan_windows.h). 1 and null for every
  // other plan.
  int refinement = 1;
  std::shared_ptr<const RefinedPixels> refined;

  const PdsmGeometry& geometry() const { return header.geometry; }
  const LightSpaceMesh& RefinableReceivers() const {
    return some_receivers_unrefined ? refinable_receivers : receivers;
  }
  bool has_casters() const { return !casters.indices.empty(); }
  // The index of the tile whose first pixel is (x0, y0). REQUIRES: a tile starts there.
  int TileIndexAt(int x0, int y0) const {
    return (y0 / header.tile_size) * tiles_x + x0 / header.tile_size;
  }
  int tile_count() const { return tiles_x * tiles_y; }
  // REQUIRES: 0 <= index < tile_count().
  TileRect tile(int index) const;
  int groups_x() const { return (tiles_x + group_side - 1) / group_side; }
  int groups_y() const { return (tiles_y + group_side - 1) / group_side; }
  int group_count() const { return groups_x() * groups_y(); }
  // Its tiles listed, row-major. REQUIRES: 0 <= index < group_count().
  TileGroup group(int index) const;
  // The group holding tile `tile`. REQUIRES: 0 <= tile < tile_count().
  int GroupOfTile(int tile) const {
    return (tile / tiles_x / group_side) * groups_x() + (tile % tiles_x) / group_side;
  }
};

// Every tile of a plan in index order, made as it is iterated (nothing stored):
// `for (const TileRect& tile : AllTiles(plan))`. The plan must outlive the loop.
class AllTiles {
 public:
  class Iterator {
   public:
    Iterator(const BakePlan* plan, int index) : plan_(plan), index_(index) {}
    TileRect operator*() const { return plan_->tile(index_); }
    Iterator& operator++() {
      ++index_;
      return *this;
    }
    bool operator!=(const Iterator& other) const { return index_ != other.index_; }

   private:
    const BakePlan* plan_;
    int index_;
  };
  explicit AllTiles(const BakePlan& plan) : plan_(&plan) {}
  Iterator begin() const { return {plan_, 0}; }
  Iterator end() const { return {plan_, plan_->tile_count()}; }

 private:
  const BakePlan* plan_;
};

// The constant depth bias used when the scene sets none: float32 depths round at about
// 6e-8 relative, the rasterizer's interpolation adds a few ulps; 1e-5 of the farthest depth
// covers both with margin. The slope-scaled part is added per texel by the renderer.
double DefaultDepthBias(double z_far);

// Largest shadow map one task renders for one sample, in texels (1 GiB of float depths).
inline constexpr int64_t kMaxShadowMapTexels = int64_t{1} << 28;
// The texel budget the scan floor is chosen for: 2^24 texels (64 MiB, 4096^2) per shadow map,
// or four times the tile's own extent when that is larger.
inline constexpr int64_t kShadowMapTexelBudget = int64_t{1} << 24;
// The texels per axis one ray may cross in one shadow map before the scan floor moves out
// (unless that would leave receivers unresolved): bounds the scan's time as the budget above
// bounds memory. Ordinary scenes walk tens of texels per ray.
inline constexpr double kMaxRayTexels = 512;

// Widest field of view a perspective PDSM is fitted to: |s|, |t| <= tan(85 degrees).
inline constexpr double kMaxWindowTangent = 11.430052302761343;

// The widest |s|, |t| a PDSM of `light` is fitted to: kMaxWindowTangent, a spot's
// tan(cone half-angle) (the square around its cone), or a sphere face's face_tangent. The
// sun's window is not a tangent.
double MaxWindowTangent(const LightSpec& light);

// The tiles a bake of these settings is cut into, known before planning: its resolution in
// tiles of tile_size (a tile size below 1 counts as 1).
int64_t TileCountOf(const BakeSettings& bake);

// A scene with nothing in front of the light gets a default frustum (window [-1, 1]^2,
// depths [1, 2]) and bakes to an all-lit PDSM. Errors: INVALID_ARGUMENT for a frustum
// override the projection cannot use.
// Which of the scene's casters a plan keeps: those some tile can reach (the default: the
// bake is byte for byte the same), or every one (to compare against).
enum class PlanCasters { kReachable, kEvery };
// The plan of the scene's own light (light, bake, light_name), through a shared index of the
// scene's triangles (core/bake/scene_index.h): a job plans every light through one.
absl::StatusOr<BakePlan> PlanBake(const SceneIndex& index,
                                  PlanCasters casters = PlanCasters::kReachable);
// Light `light` of the index's scene (LightOf's numbering), without copying its meshes: the
// plan of PlanBake(ForLight(scene, light)), bit for bit. REQUIRES: light < LightCount().
absl::StatusOr<BakePlan> PlanBake(const SceneIndex& index, size_t light,
                                  PlanCasters casters = PlanCasters::kReachable);
// The same, indexing the scene first (a sort of its triangles: a caller planning several
// lights of one scene builds the index once).
absl::StatusOr<BakePlan> PlanBake(const Scene& scene,
                                  PlanCasters casters = PlanCasters::kReachable);
absl::StatusOr<BakePlan> PlanBake(const Scene& scene, size_t light,
                                  PlanCasters casters = PlanCasters::kReachable);

// The plan of the refinement level of `base`, a plan of the same index's light `light`
// (nullopt: the scene's one-light form), for the pixels `refined` chose
// (core/bake/refined_pixels.h; docs/algorithms.md section 10), f = refined->factor(): the same
// light, bake, samples and frustum as `base` at f times its resolution and its shadow-map
// resolution, so that this plan's pixel (f x + i, f y + j) is sub-pixel (i, j) of base pixel
// (x, y) (core/pdsm/refined_pixel.h) and its maps refine the base's lattice by the same factor.
// Its rays are the sub-pixels of the refined pixels, scanned around the receivers inside their
// bands (core/bake/scan_windows.h; it keeps the receivers for that), and a tile without one has
// no task (tile_has_casters). Not itself refined, nor surfaces-only. INVALID_ARGUMENT naming
// bake.maxRefinement when the level would pass a map's limits (kMaxPdsmResolution,
// kMaxPdsmPixels, kMaxPdsmTiles). REQUIRES: refined is not empty.
absl::StatusOr<BakePlan> PlanRefinementLevel(const SceneIndex& index, std::optional<size_t> light,
                                             const BakePlan& base,
                                             std::shared_ptr<const RefinedPixels> refined);

// Sets plan->receivers to every receiver of `scene`, in the plan's light space, in scene order,
// and for a refined plan whose scene has receivers with `refine: false` the refinable ones
// (some_receivers_unrefined, refinable_receivers). REQUIRES: the plan was made of `scene`.
void AddLightSpaceReceivers(const Scene& scene, BakePlan* plan);

// Frees what only a shadow-map renderer uses: the casters and their clusters, and the
// receivers unless the plan is surfaces-only (the tile assembly places its depth windows with
// them), refined (they place the bands of its refined pixels) or a refinement level (they
// place its scan windows). What is left tiles, groups,
// numbers and assembles the bake as before; a coordinator keeps that much of each light of each job
// (a world's 10^6 triangles are ~40 MB per light, the rest a few KB). Take PlanFingerprint first:
// it covers the geometry.
void ReleaseRenderGeometry(BakePlan* plan);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_BAKE_PLAN_H_
