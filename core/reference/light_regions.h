// A polygonal light prepared once for many points: cleaned up, counter-clockwise, and cut into
// convex regions that tile it (the hidden area is the sum over regions of a union of convex
// pieces). Internal to core/reference (not a public API).
#ifndef PDSM_CORE_REFERENCE_LIGHT_REGIONS_H_
#define PDSM_CORE_REFERENCE_LIGHT_REGIONS_H_

#include <optional>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace pdsm::internal {

// A convex part of the light, counter-clockwise, with its bounding box and area.
struct Region {
  std::vector<glm::dvec2> ccw;
  glm::dvec2 lo{0.0}, hi{0.0};
  double area = 0.0;
  // Points within inner_radius of inner_center are inside: most pieces need no clipping.
  glm::dvec2 inner_center{0.0};
  double inner_radius = 0.0;
};

// The light, prepared once for many points.
struct PreparedLight {
  double area = 0.0;
  glm::dvec2 lo{0.0}, hi{0.0};  // bounding box
  double tolerance = 0.0;       // the length tolerance: 1e-10 times the light's extent
  std::vector<Region> regions;  // they tile the light
};

// `polygon` is a simple polygon, either orientation. Vertices within the tolerance of a
// neighbour or of the line through their neighbours are dropped; a convex light is one region,
// others are triangulated. Returns nullopt for a degenerate light: a non-finite vertex, fewer
// than 3 vertices left, or no positive area.
std::optional<PreparedLight> PrepareLight(std::span<const glm::dvec2> polygon);

}  // namespace pdsm::internal

#endif  // PDSM_CORE_REFERENCE_LIGHT_REGIONS_H_
