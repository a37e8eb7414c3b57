#include "core/pdsm/pdsm_exr_tiles.h"

#include <cmath>

#include "absl/strings/str_format.h"

namespace pdsm {

absl::Status CheckTileFunctions(const PdsmTile& tile, absl::string_view path) {
  const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
  if (tile.offsets[0] != 0 || tile.offsets[pixels] != tile.vertices.size()) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: tile (%d, %d): offsets do not span the %d vertices", path, tile.x0,
                        tile.y0, tile.vertices.size()));
  }
  if (tile.vertices.size() > kMaxVerticesPerTile) {
    return absl::InvalidArgumentError(
        absl::StrFormat("%s: tile (%d, %d) has %d vertices, more than a deep EXR tile holds (%d)",
                        path, tile.x0, tile.y0, tile.vertices.size(), kMaxVerticesPerTile));
  }
  for (size_t p = 0; p < pixels; ++p) {
    const uint64_t begin = tile.offsets[p], end = tile.offsets[p + 1];
    if (end < begin) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: tile (%d, %d): offsets decrease at pixel %d", path, tile.x0, tile.y0, p));
    }
    for (uint64_t k = begin; k < end; ++k) {
      const float z = tile.vertices[k].z;
      if (std::isnan(z) || (k > begin && z < tile.vertices[k - 1].z)) {
        return absl::InvalidArgumentError(
            absl::StrFormat("%s: pixel (%d, %d): vertex depths are not nondecreasing", path,
                            tile.x0 + static_cast<int>(p % tile.width),
                            tile.y0 + static_cast<int>(p / tile.width)));
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace pdsm
