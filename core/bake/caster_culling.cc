#include "core/bake/caster_culling.h"

#include <array>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake/tile_reach.h"

namespace pdsm {
namespace {

constexpr uint32_t kUnset = std::numeric_limits<uint32_t>::max();

// Scene vertices in the light's frame, as float, each transformed once however many
// triangles or questions ask for it. A mesh's lookup table is made when first asked.
class LightVertices {
 public:
  LightVertices(const Scene& scene, const LightFrame& frame)
      : scene_(scene), frame_(frame), slots_(scene.meshes.size()) {}

  // The slot of vertex `v` of mesh `mesh` in positions().
  uint32_t Slot(uint32_t mesh, uint32_t v) {
    std::vector<uint32_t>& slots = slots_[mesh];
    if (slots.empty()) slots.assign(scene_.meshes[mesh].positions_world.size(), kUnset);
    if (slots[v] == kUnset) {
      slots[v] = static_cast<uint32_t>(positions_.size());
      positions_.push_back(
          glm::vec3(frame_.LightFromWorld(scene_.meshes[mesh].positions_world[v])));
    }
    return slots[v];
  }
  std::array<uint32_t, 3> Slots(const SceneTriangle& t) {
    const std::vector<uint32_t>& indices = scene_.meshes[t.mesh].indices;
    return {Slot(t.mesh, indices[3 * size_t{t.triangle}]),
            Slot(t.mesh, indices[3 * size_t{t.triangle} + 1]),
            Slot(t.mesh, indices[3 * size_t{t.triangle} + 2])};
  }
  // The triangle as the plan's casters will hold it (float vertices, read as double).
  std::array<glm::dvec3, 3> Triangle(const SceneTriangle& t) {
    const std::array<uint32_t, 3> s = Slots(t);
    return {glm::dvec3(positions_[s[0]]), glm::dvec3(positions_[s[1]]),
            glm::dvec3(positions_[s[2]])};
  }
  const std::vector<glm::vec3>& positions() const { return positions_; }
  // Hands the positions over; asking for a vertex not yet transformed afterwards is an error.
  std::vector<glm::vec3> TakePositions() { return std::move(positions_); }

 private:
  const Scene& scene_;
  const LightFrame& frame_;
  std::vector<std::vector<uint32_t>> slots_;  // per mesh, per vertex; kUnset: not yet
  std::vector<glm::vec3> positions_;
};

// The tiles marked by every caster cluster of the index (core/bake/caster_culling.h: whatever
// is left out).
std::vector<bool> MarkTiles(const SceneIndex& index, const std::vector<CasterBox>& boxes,
                            LightVertices* vertices, const BakePlan& plan) {
  return TilesCastersMayReach(
      plan, boxes, [&](size_t i, std::vector<std::pair<glm::dvec3, glm::dvec3>>* out) {
        const SceneCluster& c = index.clusters()[i];
        for (uint32_t k = c.first; k < c.first + c.count; ++k) {
          const std::array<glm::dvec3, 3> p = vertices->Triangle(index.triangles()[k]);
          out->emplace_back(glm::min(glm::min(p[0], p[1]), p[2]),
                            glm::max(glm::max(p[0], p[1]), p[2]));
        }
      });
}

}  // namespace

void GatherCasters(const SceneIndex& index, PlanCasters which, BakePlan* plan) {
  const Scene& scene = index.scene();
  const LightFrame& frame = plan->geometry().frame;
  LightVertices vertices(scene, frame);

  // The caster clusters come first in the index's order.
  std::vector<CasterBox> boxes;
  for (const SceneCluster& c : index.clusters()) {
    if (!c.casts) break;
    const LightBox box = LightBoxOf(frame, c.lo, c.hi);
    boxes.push_back(CasterBox{box.lo, box.hi, c.count});
  }
  plan->tile_has_casters = MarkTiles(index, boxes, &vertices, *plan);

  // The kept triangles, cluster by cluster, in order.
  const CasterReachBound bound(*plan);
  std::vector<SceneTriangle> kept;
  std::vector<CasterCluster> clusters;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const SceneCluster& c = index.clusters()[i];
    if (which == PlanCasters::kReachable && !bound.BoxMayReach(boxes[i].lo, boxes[i].hi)) continue;
    CasterCluster cluster;
    cluster.first_triangle = static_cast<uint32_t>(kept.size());
    cluster.mask = static_cast<uint16_t>(c.group);
    cluster.lo = glm::dvec3(std::numeric_limits<double>::infinity());
    cluster.hi = -cluster.lo;
    for (uint32_t k = c.first; k < c.first + c.count; ++k) {
      const SceneTriangle& t = index.triangles()[k];
      const std::array<glm::dvec3, 3> p = vertices.Triangle(t);
      if (which == PlanCasters::kReachable && !bound.TriangleMayReach(p)) continue;
      kept.push_back(t);
      for (const glm::dvec3& v : p) {
        cluster.lo = glm::min(cluster.lo, v);
        cluster.hi = glm::max(cluster.hi, v);
      }
    }
    cluster.triangle_count = static_cast<uint32_t>(kept.size()) - cluster.first_triangle;
    if (cluster.triangle_count > 0) clusters.push_back(cluster);
  }
  plan->caster_clusters = std::move(clusters);
  plan->casters_left_out = index.caster_count() - kept.size();

  // Their vertices: the transformed ones they use, in the order they were transformed,
  // compacted in place (a sun keeps nearly all: no second copy of the world).
  LightSpaceMesh& mesh = plan->casters;
  mesh = LightSpaceMesh{};
  const bool masked = !index.masks().empty();
  mesh.indices.reserve(3 * kept.size());
  std::vector<glm::vec2> uv_of_slot;
  if (masked) {
    uv_of_slot.resize(vertices.positions().size());
    mesh.triangle_masks.reserve(kept.size());
  }
  for (const SceneTriangle& t : kept) {
    const TriangleMesh& source = scene.meshes[t.mesh];
    const std::array<uint32_t, 3> slots = vertices.Slots(t);
    mesh.indices.insert(mesh.indices.end(), slots.begin(), slots.end());
    if (!masked) continue;
    for (int v = 0; v < 3; ++v) {
      const uint32_t source_vertex = source.indices[3 * size_t{t.triangle} + v];
      uv_of_slot[slots[v]] = source.has_masks() ? source.uvs[source_vertex] : glm::vec2(0.0f);
    }
    const std::vector<uint16_t>& numbers = index.MaskNumbers(t.mesh);
    mesh.triangle_masks.push_back(numbers.empty() ? 0 : numbers[source.triangle_masks[t.triangle]]);
  }
  mesh.positions = vertices.TakePositions();
  std::vector<uint32_t> vertex_of_slot(mesh.positions.size(), kUnset);
  for (const uint32_t slot : mesh.indices) vertex_of_slot[slot] = 0;
  uint32_t used = 0;
  for (size_t slot = 0; slot < mesh.positions.size(); ++slot) {
    if (vertex_of_slot[slot] == kUnset) continue;
    vertex_of_slot[slot] = used;
    mesh.positions[used] = mesh.positions[slot];
    if (masked) mesh.uvs.push_back(uv_of_slot[slot]);
    ++used;
  }
  mesh.positions.resize(used);
  if (used <= mesh.positions.capacity() / 2) mesh.positions.shrink_to_fit();
  for (uint32_t& i : mesh.indices) i = vertex_of_slot[i];
  plan->masks = index.masks();
}

}  // namespace pdsm
