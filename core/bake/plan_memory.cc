#include "core/bake/plan_memory.h"

#include <algorithm>
#include <string>
#include <vector>

#include "core/bake/refined_pixels.h"

namespace pdsm {
namespace {

template <typename T>
int64_t VectorBytes(const std::vector<T>& v) {
  return static_cast<int64_t>(v.capacity() * sizeof(T));
}

int64_t VectorBytes(const std::vector<bool>& v) {
  return static_cast<int64_t>((v.capacity() + 7) / 8);
}

// A string's heap block; short strings live inside the object.
int64_t StringBytes(const std::string& s) {
  return s.capacity() > std::string().capacity() ? static_cast<int64_t>(s.capacity() + 1) : 0;
}

int64_t MeshBytes(const LightSpaceMesh& mesh) {
  return VectorBytes(mesh.positions) + VectorBytes(mesh.indices) + VectorBytes(mesh.uvs) +
         VectorBytes(mesh.triangle_masks);
}

}  // namespace

int64_t PlanHeldBytes(const BakePlan& plan) {
  int64_t bytes = sizeof(BakePlan);
  const PdsmHeader& h = plan.header;
  bytes += StringBytes(h.scene_name) + StringBytes(h.light_name) + VectorBytes(h.tile_samples);
  // Tiles and groups are made on demand (BakePlan::tile, group): a bit per tile is all.
  bytes += VectorBytes(plan.samples) + VectorBytes(plan.tile_has_casters);
  bytes += MeshBytes(plan.casters) + VectorBytes(plan.caster_clusters) + MeshBytes(plan.receivers) +
           MeshBytes(plan.refinable_receivers);
  // Masks are shared with the scene; counted here as if the plan held them alone.
  bytes += VectorBytes(plan.masks);
  for (const auto& mask : plan.masks) bytes += sizeof(AlphaMask) + VectorBytes(mask->alpha);
  // A refinement level's pixels (shared with whoever chose them; counted here, with the level).
  if (plan.refined) bytes += plan.refined->HeldBytes();
  return bytes;
}

int64_t MinReleasedPlanBytes(const BakeSettings& bake, int64_t receiver_vertices,
                             int64_t receiver_triangles) {
  const int64_t tiles = TileCountOf(bake);
  int64_t bytes = sizeof(BakePlan);
  bytes += int64_t{bake.samples} * static_cast<int64_t>(sizeof(glm::dvec2));
  bytes += (tiles + 7) / 8;  // tile_has_casters
  if (bake.surfaces_only) {
    // Kept at their exact size (ReleaseRenderGeometry).
    bytes += receiver_vertices * static_cast<int64_t>(sizeof(glm::vec3)) +
             3 * receiver_triangles * static_cast<int64_t>(sizeof(uint32_t));
  }
  return bytes;
}

}  // namespace pdsm
