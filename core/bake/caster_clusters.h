// Casters in clusters (thesis 3.3; issue #11 "submit only what a map can see"): the plan's
// caster triangles in a spatial order (meshoptimizer's Morton-curve sort) cut into runs of
// kClusterTriangles, each with its light-space bounding box. Tile reach tests a cluster's box
// before its triangles (core/bake/tile_reach.h), and each shadow map draws only the clusters
// whose box its window and depth range can see (worker/bake_task.cc).
#ifndef PDSM_CORE_BAKE_CASTER_CLUSTERS_H_
#define PDSM_CORE_BAKE_CASTER_CLUSTERS_H_

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

namespace pdsm {

struct LightSpaceMesh;

// Large enough that a 200k-triangle mesh is a few thousand boxes, small enough that a box
// stays near its triangles.
inline constexpr uint32_t kClusterTriangles = 128;

// Triangles [first_triangle, first_triangle + triangle_count) of the casters' index order.
struct CasterCluster {
  uint32_t first_triangle = 0;
  uint32_t triangle_count = 0;
  uint16_t mask = 0;            // every triangle's: 0 opaque, k the plan's masks[k - 1]
  glm::dvec3 lo{0.0}, hi{0.0};  // bounds of its vertices, light space (exact: float -> double)
};

// Sorts `mesh`'s triangles spatially (each triangle's vertex order is kept) and returns the
// clusters covering them, in order. Alpha-tested triangles (mesh->triangle_masks) come after
// the opaque ones, grouped by mask, each group sorted on its own: a cluster never mixes masks.
// Deterministic: the order depends only on the mesh.
std::vector<CasterCluster> ClusterCasters(LightSpaceMesh* mesh);

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_CASTER_CLUSTERS_H_
