#include "worker/preview_image.h"

#include <cmath>

#include "core/util/png_writer.h"

namespace pdsm {

PreviewImage::PreviewImage(int width, int height)
    : width_(width), height_(height), rgb_(static_cast<size_t>(width) * height * 3, 0) {}

void PreviewImage::ShadeTile(const PdsmTile& tile, std::span<const float> receiver_depth) {
  for (int j = 0; j < tile.height; ++j) {
    for (int i = 0; i < tile.width; ++i) {
      const float z = receiver_depth[static_cast<size_t>(j) * tile.width + i];
      uint8_t rgb[3] = {24, 28, 52};
      if (std::isfinite(z)) {
        const double lit = 1.0 - EvaluateAttenuation(tile.Function(i, j), z);
        const auto gray = static_cast<uint8_t>(std::lround(36 + 219 * lit));
        rgb[0] = rgb[1] = rgb[2] = gray;
      }
      // u x v = n points away from a viewer at the light, so u runs right-to-left on screen.
      const int column = width_ - 1 - (tile.x0 + i);
      const int row = height_ - 1 - (tile.y0 + j);
      uint8_t* out = &rgb_[(static_cast<size_t>(row) * width_ + column) * 3];
      out[0] = rgb[0];
      out[1] = rgb[1];
      out[2] = rgb[2];
    }
  }
}

absl::Status PreviewImage::Write(const std::string& path, FileSystem* fs) const {
  return WriteRgbPng(path, width_, height_, rgb_, fs);
}

}  // namespace pdsm
