// Casters in clusters (thesis 3.3; issue #11 "submit only what a map can see"): the plan's
// caster triangles in the scene index's spatial order (core/bake/scene_index.h), each of the
// index's clusters keeping the triangles the light keeps, with their light-space bounding box. Tile
// reach tests a cluster's box before its triangles (core/bake/tile_reach.h), and each shadow map
// draws only the clusters whose box its window and depth range can see (worker/bake_task.cc).
#ifndef PDSM_CORE_BAKE_CASTER_CLUSTERS_H_
#define PDSM_CORE_BAKE_CASTER_CLUSTERS_H_

#include <cstdint>

#include <glm/glm.hpp>

namespace pdsm {

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

}  // namespace pdsm

#endif  // PDSM_CORE_BAKE_CASTER_CLUSTERS_H_
