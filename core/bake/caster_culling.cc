#include "core/bake/caster_culling.h"

#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include <glm/glm.hpp>

#include "core/bake/bake_plan.h"
#include "core/bake/tile_reach.h"

namespace pdsm {
namespace {

// Gives `v` back the memory it no longer uses when that is at least half of it: a local
// light's plan drops a world's worth, while a sun that keeps nearly everything would only pay
// for a second copy.
template <typename T>
void ShrinkIfHalfEmpty(std::vector<T>* v) {
  if (v->size() <= v->capacity() / 2) v->shrink_to_fit();
}

}  // namespace

size_t LeaveOutUnreachableCasters(BakePlan* plan) {
  const std::vector<bool> keep = CastersSomeTileMayReach(*plan);
  size_t kept = 0;
  for (bool k : keep) kept += k ? 1 : 0;
  if (kept == keep.size()) return 0;

  // Compacted in place, in order: a kept triangle or vertex never moves up.
  LightSpaceMesh& mesh = plan->casters;
  constexpr uint32_t kUnused = std::numeric_limits<uint32_t>::max();
  std::vector<uint32_t> new_vertex(mesh.positions.size(), kUnused);
  for (size_t t = 0; t < keep.size(); ++t) {
    if (!keep[t]) continue;
    for (int v = 0; v < 3; ++v) new_vertex[mesh.indices[3 * t + v]] = 0;
  }
  size_t vertices = 0;
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    if (new_vertex[i] == kUnused) continue;
    new_vertex[i] = static_cast<uint32_t>(vertices);
    mesh.positions[vertices] = mesh.positions[i];
    if (!mesh.uvs.empty()) mesh.uvs[vertices] = mesh.uvs[i];
    ++vertices;
  }

  size_t triangles = 0;
  std::vector<CasterCluster> clusters;
  for (const CasterCluster& c : plan->caster_clusters) {
    CasterCluster next;
    next.first_triangle = static_cast<uint32_t>(triangles);
    next.mask = c.mask;
    next.lo = glm::dvec3(std::numeric_limits<double>::infinity());
    next.hi = -next.lo;
    for (size_t t = c.first_triangle; t < size_t{c.first_triangle} + c.triangle_count; ++t) {
      if (!keep[t]) continue;
      for (int v = 0; v < 3; ++v) {
        const uint32_t index = new_vertex[mesh.indices[3 * t + v]];
        mesh.indices[3 * triangles + v] = index;
        next.lo = glm::min(next.lo, glm::dvec3(mesh.positions[index]));
        next.hi = glm::max(next.hi, glm::dvec3(mesh.positions[index]));
      }
      if (!mesh.triangle_masks.empty()) mesh.triangle_masks[triangles] = mesh.triangle_masks[t];
      ++triangles;
      ++next.triangle_count;
    }
    if (next.triangle_count > 0) clusters.push_back(next);
  }
  mesh.positions.resize(vertices);
  mesh.indices.resize(3 * triangles);
  if (!mesh.uvs.empty()) mesh.uvs.resize(vertices);
  if (!mesh.triangle_masks.empty()) mesh.triangle_masks.resize(triangles);
  ShrinkIfHalfEmpty(&mesh.positions);
  ShrinkIfHalfEmpty(&mesh.indices);
  ShrinkIfHalfEmpty(&mesh.uvs);
  ShrinkIfHalfEmpty(&mesh.triangle_masks);
  plan->caster_clusters = std::move(clusters);
  return keep.size() - kept;
}

}  // namespace pdsm
