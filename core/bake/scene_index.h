// A scene's triangles in one world-space spatial order, cut into clusters with world boxes,
// made once and shared by every light a job plans (issue #12, large worlds). A light's plan
// fits its frustum by pruning whole clusters (core/bake/window_fit.h), and takes its casters
// from the clusters some tile can reach, so that a street lamp in a world of 10^6 triangles
// transforms and sorts the few hundred near it, not the world.
//
// The order is a Morton curve over the scene's bounds, so the order of any subset is its order
// within the whole: a light's kept casters are drawn in the same relative order whatever else
// it keeps (draw order settles depth ties).
#ifndef PDSM_CORE_BAKE_SCENE_INDEX_H_
#define PDSM_CORE_BAKE_SCENE_INDEX_H_

#include <cstdint>
#include <memory>
#include <vector>

#include <glm/glm.hpp>

#include "absl/status/statusor.h"
#include "core/geometry/light_frame.h"
#include "core/scene/alpha_mask.h"
#include "core/scene/scene.h"

namespace pdsm {

// Triangle `triangle` (its indices at 3 * triangle) of scene.meshes[mesh].
struct SceneTriangle {
  uint32_t mesh = 0;
  uint32_t triangle = 0;
};

// Consecutive triangles [first, first + count) of the index's order, all of one group: the
// casters of one alpha mask (group = the plan's mask index, 0 opaque) or receivers that do not
// cast (group kReceiverOnlyGroup).
struct SceneCluster {
  uint32_t first = 0;
  uint32_t count = 0;
  uint32_t group = 0;
  bool casts = false;           // group < kReceiverOnlyGroup
  bool receives = false;        // some triangle of it receives
  glm::dvec3 lo{0.0}, hi{0.0};  // world bounds of its triangles' vertices (exact)
};

inline constexpr uint32_t kReceiverOnlyGroup = 0x10000;

// Axis-aligned box in a light's frame holding every point of a world box, each coordinate as
// LightFromWorld computes it, and as float rounds that: the least and greatest of both, exactly
// (each rounded step is monotone, so they are at corners).
struct LightBox {
  glm::dvec3 lo, hi;
};
LightBox LightBoxOf(const LightFrame& frame, const glm::dvec3& world_lo,
                    const glm::dvec3& world_hi);

// Immutable once built; safe to share between threads. Holds a pointer to the scene, which
// must outlive it unchanged. Memory: 8 bytes per triangle and 80 per 128 of them.
class SceneIndex {
 public:
  // Errors: INVALID_ARGUMENT naming the scene file when its casters use more than 65535
  // distinct alpha masks.
  static absl::StatusOr<std::shared_ptr<const SceneIndex>> Build(const Scene& scene);

  const Scene& scene() const { return *scene_; }
  // The bounds of every vertex of every mesh; empty() when there is none.
  const glm::dvec3& lo() const { return lo_; }
  const glm::dvec3& hi() const { return hi_; }
  bool empty() const { return lo_.x > hi_.x; }

  // Every triangle of every mesh: casters first, grouped by mask (opaque first), then the
  // receivers that do not cast; spatially sorted within each group.
  const std::vector<SceneTriangle>& triangles() const { return triangles_; }
  size_t caster_count() const { return caster_count_; }  // triangles_[0, caster_count())
  // Runs of at most kClusterTriangles of the order, never across groups.
  const std::vector<SceneCluster>& clusters() const { return clusters_; }
  // A tree over the clusters for pruned searches: tree()[0][i] bounds clusters [8 i, 8 i + 8),
  // tree()[k][i] bounds tree()[k - 1][8 i, 8 i + 8); the last level has one box (none when
  // there are no clusters).
  static constexpr size_t kTreeFanout = 8;
  struct Box {
    glm::dvec3 lo, hi;
    bool casts = false, receives = false;
  };
  const std::vector<std::vector<Box>>& tree() const { return tree_; }

  // The casters' alpha masks in plan numbering (1-based in triangle groups; equal masks of
  // different meshes are one), and per mesh the plan number of its masks[k - 1] at [k].
  const std::vector<std::shared_ptr<const AlphaMask>>& masks() const { return masks_; }
  const std::vector<uint16_t>& MaskNumbers(size_t mesh) const { return mask_numbers_[mesh]; }

 private:
  const Scene* scene_ = nullptr;
  glm::dvec3 lo_{1.0}, hi_{-1.0};
  std::vector<SceneTriangle> triangles_;
  size_t caster_count_ = 0;
  std::vector<SceneCluster> clusters_;
  std::vector<std::vector<Box>> tree_;
  std::vector<std::shared_ptr<const AlphaMask>> masks_;
  std::vector<std::vector<uint16_t>> mask_numbers_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_SCENE_INDEX_H_
