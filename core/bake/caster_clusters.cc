#include "core/bake/caster_clusters.h"

#include <meshoptimizer.h>

#include <algorithm>

#include "core/bake/bake_plan.h"

namespace pdsm {
namespace {

// Cuts triangles [first, end) of `mesh` (all with mask `mask`) into clusters.
void CutClusters(const LightSpaceMesh& mesh, size_t first, size_t end, uint16_t mask,
                 std::vector<CasterCluster>* clusters) {
  for (; first < end; first += kClusterTriangles) {
    CasterCluster c;
    c.first_triangle = static_cast<uint32_t>(first);
    c.triangle_count = static_cast<uint32_t>(std::min<size_t>(kClusterTriangles, end - first));
    c.mask = mask;
    c.lo = glm::dvec3(mesh.positions[mesh.indices[3 * first]]);
    c.hi = c.lo;
    for (size_t i = 3 * first; i < 3 * (first + c.triangle_count); ++i) {
      const glm::dvec3 p(mesh.positions[mesh.indices[i]]);
      c.lo = glm::min(c.lo, p);
      c.hi = glm::max(c.hi, p);
    }
    clusters->push_back(c);
  }
}

// Morton order of the triangles' centroids: neighbours in the order are neighbours in space.
std::vector<uint32_t> SpatialOrder(const std::vector<uint32_t>& indices,
                                   const LightSpaceMesh& mesh) {
  std::vector<uint32_t> sorted(indices.size());
  meshopt_spatialSortTriangles(sorted.data(), indices.data(), indices.size(), &mesh.positions[0].x,
                               mesh.positions.size(), sizeof(glm::vec3));
  return sorted;
}

}  // namespace

std::vector<CasterCluster> ClusterCasters(LightSpaceMesh* mesh) {
  std::vector<CasterCluster> clusters;
  const size_t triangles = mesh->TriangleCount();
  if (triangles == 0) return clusters;
  if (mesh->triangle_masks.empty()) {
    mesh->indices = SpatialOrder(mesh->indices, *mesh);
    CutClusters(*mesh, 0, triangles, 0, &clusters);
    return clusters;
  }
  // Alpha-tested casters: the opaque triangles first, then each mask's, each run sorted on its
  // own, so that a cluster (a draw range) has one mask and one program draws it.
  std::vector<std::vector<uint32_t>> runs;  // by mask
  for (size_t t = 0; t < triangles; ++t) {
    const uint16_t mask = mesh->triangle_masks[t];
    if (runs.size() <= mask) runs.resize(mask + size_t{1});
    runs[mask].insert(runs[mask].end(), mesh->indices.begin() + 3 * t,
                      mesh->indices.begin() + 3 * t + 3);
  }
  std::vector<uint32_t> indices;
  std::vector<uint16_t> masks;
  indices.reserve(mesh->indices.size());
  masks.reserve(triangles);
  for (size_t mask = 0; mask < runs.size(); ++mask) {
    if (runs[mask].empty()) continue;
    const std::vector<uint32_t> sorted = SpatialOrder(runs[mask], *mesh);
    indices.insert(indices.end(), sorted.begin(), sorted.end());
    masks.insert(masks.end(), sorted.size() / 3, static_cast<uint16_t>(mask));
  }
  mesh->indices = std::move(indices);
  mesh->triangle_masks = std::move(masks);
  for (size_t first = 0; first < triangles;) {
    size_t end = first;
    while (end < triangles && mesh->triangle_masks[end] == mesh->triangle_masks[first]) ++end;
    CutClusters(*mesh, first, end, mesh->triangle_masks[first], &clusters);
    first = end;
  }
  return clusters;
}

}  // namespace pdsm
