// A PDSM in memory: its header (geometry and bake metadata) and one attenuation function per
// pixel, stored two-level as the thesis proposes (4.2.4): offsets into one vertex array.
#ifndef PDSM_CORE_PDSM_PDSM_IMAGE_H_
#define PDSM_CORE_PDSM_PDSM_IMAGE_H_

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "core/events/event.h"
#include "core/pdsm/attenuation_function.h"
#include "core/pdsm/pdsm_geometry.h"
#include "core/scene/scene.h"

namespace pdsm {

// The newest format this build reads and writes (docs/pdsm_format.md, "Versioning").
inline constexpr int kPdsmFormatVersion = 3;

// Everything a reader needs to evaluate the PDSM and to know how it was made.
struct PdsmHeader {
  int format_version = 1;  // MinimumFormatVersion(*this) for what a bake writes
  std::string scene_name;
  // The light's name from the scene (Light.name): the OpenEXR part's `name` attribute. Empty
  // for a single light given no name (no `name` attribute: the file of a one-light scene is
  // what it was before lights had names).
  std::string light_name;
  LightShape light_shape = LightShape::kRect;
  // The light's size. Lengths are world units, which are also light-space units: the light
  // frame (u, v, n) is orthonormal. Rect: half extents along u and v; disk: radius (0 for
  // the other shapes); sun: tan of half its angular diameter (dimensionless, 0 otherwise).
  double light_half_width = 0, light_half_height = 0, light_radius = 0, tan_half_angle = 0;
  // A spot light (a disk into a cone; LightSpec::cone_half_angle_deg): the cone's half-angle,
  // degrees; 0 for every other light. Informational: the window already stops at the cone.
  double cone_half_angle_deg = 0;
  // A face of a sphere light (LightSpec::face_tangent; core/scene/sphere_faces.h): the bound
  // on |s|, |t| of the face's directions; 0 for every other light. The part is the face's disk,
  // named "SPHERE@FACE"; readers take the sphere's faces together (core/pdsm/pdsm_lights.h).
  double face_tangent = 0;
  PdsmGeometry geometry;
  int samples = 0;
  int shadow_map_resolution = 0;
  double epsilon = 0;
  CompressionMetric compression_metric = CompressionMetric::kVertical;
  // What each sample counted for (kUnweighted or kEmitter, core/events/emitter_weighting.h):
  // the definition of the stored A. Readers evaluate either the same way.
  LightWeighting weighting = LightWeighting::kUnweighted;
  // Bias of the stored shadow-map depths, applied when the maps are rendered (one bias
  // function: shaders/shadow_map.frag BiasedDepth):
  //   z + depth_bias + slope_bias * footprint * (|dz/dx| + |dz/dy|)
  // depth_bias: light-space depth, world units, as applied (scene value or DefaultDepthBias).
  // slope_bias: dimensionless, a multiple of the caster's depth change across one shadow-map
  // texel (the screen-space derivatives of z), widened by footprint = max(1, PDSM pixel pitch
  // / shadow-map texel pitch) because a PDSM ray's lookups can land that far apart.
  double depth_bias = 0;
  double slope_bias = 0;
  SamplingPattern sampling = SamplingPattern::kSobol;
  uint64_t seed = 0;
  int tile_size = 0;  // PDSM pixels per tile side, also the EXR tile size
  // Adaptive sampling (docs/algorithms.md); 0 when off. `samples` is then the per-tile maximum
  // and tile t was baked with the first tile_samples[t] samples (row-major tile order).
  // tile_samples is empty for fixed-count bakes and in the header a bake starts writing with.
  double adaptive_tolerance = 0;
  int adaptive_min_samples = 0;
  std::vector<int> tile_samples;

  bool adaptive() const { return adaptive_tolerance > 0; }
  // Light samples behind the functions of tile `tile_index`.
  int TileSamples(size_t tile_index) const {
    return tile_index < tile_samples.size() ? tile_samples[tile_index] : samples;
  }
  // Surfaces-only bake (docs/algorithms.md): functions hold only depth windows around the
  // receiver surfaces; elsewhere they evaluate to NaN (attenuation NaN vertices bracket the
  // windows), or to 0 in pixels that hold no vertex.
  bool surfaces_only = false;
  // Adaptive resolution (issue #15 item 2; docs/pdsm_format.md "Refined pixels"): the largest
  // refinement a pixel of this PDSM may hold, 1 (none), 2, 4 or 8. Above 1, pixels may be
  // refined (core/pdsm/refined_pixel.h) and the file is format version 3.
  int max_refinement = 1;
};

// Version 2 changed the evaluation rule (NaN nearer than z_valid_min, NaN-bracketed
// surfaces-only windows); version 3 added refined pixels. A file is written with the oldest
// version its features need, so an older reader still opens every file that uses none of the
// newer features, and their bytes did not change.
inline int MinimumFormatVersion(const PdsmHeader& h) {
  if (h.max_refinement > 1) return 3;
  return h.surfaces_only || h.geometry.z_valid_min != 0 ? 2 : 1;
}

// Whether the bake's events are keyed by sample (core/events/event.h): emitter weighting of a
// planar light, the only case where samples weigh differently. A sun's sample directions and a
// sphere face's samples (spread by solid angle) weigh the same, so their bakes count.
inline EventKeying KeyingOf(const PdsmHeader& h) {
  const bool planar = h.geometry.projection == Projection::kPerspective && h.face_tangent == 0;
  return h.weighting == LightWeighting::kEmitter && planar ? EventKeying::kSampleKeys
                                                           : EventKeying::kCounts;
}

// One rectangle of pixels with their functions: the unit of writing and of assembling.
struct PdsmTile {
  int x0 = 0, y0 = 0;  // first pixel
  int width = 0, height = 0;
  int samples = 0;  // light samples behind its functions (adaptive bakes); 0: header.samples
  std::vector<uint64_t> offsets;  // width * height + 1, row-major from (x0, y0)
  std::vector<Vertex> vertices;

  std::span<const Vertex> Function(int local_x, int local_y) const {
    const size_t p = static_cast<size_t>(local_y) * width + local_x;
    return {vertices.data() + offsets[p], vertices.data() + offsets[p + 1]};
  }
};

struct PdsmImage {
  PdsmHeader header;
  std::vector<uint64_t> offsets;  // width * height + 1, row-major
  std::vector<Vertex> vertices;

  std::span<const Vertex> Function(int x, int y) const {
    const size_t p = static_cast<size_t>(y) * header.geometry.width + x;
    return {vertices.data() + offsets[p], vertices.data() + offsets[p + 1]};
  }
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_IMAGE_H_
