#include "core/bake/caster_clusters.h"

#include <meshoptimizer.h>

#include <algorithm>

#include "core/bake/bake_plan.h"

namespace pdsm {

std::vector<CasterCluster> ClusterCasters(LightSpaceMesh* mesh) {
  std::vector<CasterCluster> clusters;
  const size_t triangles = mesh->TriangleCount();
  if (triangles == 0) return clusters;
  // Morton order of the triangles' centroids: neighbours in the order are neighbours in space.
  std::vector<uint32_t> sorted(mesh->indices.size());
  meshopt_spatialSortTriangles(sorted.data(), mesh->indices.data(), mesh->indices.size(),
                               &mesh->positions[0].x, mesh->positions.size(), sizeof(glm::vec3));
  mesh->indices = std::move(sorted);
  for (size_t first = 0; first < triangles; first += kClusterTriangles) {
    CasterCluster c;
    c.first_triangle = static_cast<uint32_t>(first);
    c.triangle_count =
        static_cast<uint32_t>(std::min<size_t>(kClusterTriangles, triangles - first));
    c.lo = glm::dvec3(mesh->positions[mesh->indices[3 * first]]);
    c.hi = c.lo;
    for (size_t i = 3 * first; i < 3 * (first + c.triangle_count); ++i) {
      const glm::dvec3 p(mesh->positions[mesh->indices[i]]);
      c.lo = glm::min(c.lo, p);
      c.hi = glm::max(c.hi, p);
    }
    clusters.push_back(c);
  }
  return clusters;
}

}  // namespace pdsm
