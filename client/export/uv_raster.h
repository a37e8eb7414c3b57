// A texture laid over a mesh's UV charts (a lightmap), rasterised conservatively: which texels
// the charts touch and the surface point each texel stands for; then the charts' borders
// dilated so that bilinear lookups near a seam never blend in texels no chart covers.
//
// Texel (column c, row r) covers [c, c + 1] / width x [r, r + 1] / height in UV space; row 0 is
// v = 0, the image's top row (glTF's convention, and core/scene/lightmap_parts.h's UVs).
#ifndef PDSM_CLIENT_EXPORT_UV_RASTER_H_
#define PDSM_CLIENT_EXPORT_UV_RASTER_H_

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

namespace pdsm {

enum class TexelCoverage : uint8_t {
  kNone = 0,     // no triangle touches the texel
  kOverlap = 1,  // a triangle overlaps the texel but not its centre: the point is the
                 // triangle's point nearest the centre (the nearest such triangle's)
  kCentre = 2,   // the texel's centre lies in a triangle: the point is there (the first
                 // triangle's, in index order, when the centre is on a shared edge)
};

struct ChartRaster {
  int width = 0, height = 0;
  std::vector<TexelCoverage> coverage;  // width * height, row-major
  std::vector<glm::dvec3> points;       // per texel, world space; (0, 0, 0) where kNone

  size_t Index(int column, int row) const { return static_cast<size_t>(row) * width + column; }
};

// Rasterises the triangles of `indices` (3 per triangle, into `points_world` and `uvs`, one
// per vertex) into a width x height texture. Triangles with no area in UV space cover
// nothing; parts of charts outside [0, 1]^2 are clipped. Deterministic: the same input gives
// the same raster on any machine (double arithmetic, fixed order).
// REQUIRES: width, height > 0; every index < points_world.size() == uvs.size().
ChartRaster RasterizeCharts(std::span<const glm::dvec3> points_world,
                            std::span<const uint32_t> indices, std::span<const glm::vec2> uvs,
                            int width, int height);

// Texels a side of a square texture giving the charts `texels_per_unit` texels per world unit
// on average: texels_per_unit * sqrt(world area / UV area), rounded up, at least 1. 0 when the
// charts have no area (in UV space or in the world). REQUIRES: texels_per_unit > 0.
int TextureSideFor(std::span<const glm::dvec3> points_world, std::span<const uint32_t> indices,
                   std::span<const glm::vec2> uvs, double texels_per_unit);

// Grows the covered region by up to `passes` texels: each pass gives every uncovered texel
// with a covered 8-neighbour the mean of those neighbours' values (channels each), and counts
// it covered for the next pass. `values` holds `channels` floats per texel; `covered` one flag
// per texel, updated. Texels still uncovered keep their values.
void DilateCharts(int width, int height, int channels, int passes, std::vector<float>* values,
                  std::vector<uint8_t>* covered);

}  // namespace pdsm

#endif  // PDSM_CLIENT_EXPORT_UV_RASTER_H_
