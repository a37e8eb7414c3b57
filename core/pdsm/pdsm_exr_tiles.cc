#include "core/pdsm/pdsm_exr_tiles.h"

#include <cmath>
#include <span>
#include <string>

#include "absl/strings/str_format.h"
#include "core/pdsm/refined_pixel.h"

namespace pdsm {

absl::Status CheckTileFunctions(const PdsmTile& tile, absl::string_view path, int max_refinement) {
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
    const std::string fault = PixelFunctionFault(
        std::span<const Vertex>(tile.vertices.data() + begin, end - begin), max_refinement);
    if (!fault.empty()) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: pixel (%d, %d): %s", path, tile.x0 + static_cast<int>(p % tile.width),
          tile.y0 + static_cast<int>(p / tile.width), fault));
    }
  }
  return absl::OkStatus();
}

}  // namespace pdsm
