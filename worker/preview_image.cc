#include "worker/preview_image.h"

#include <algorithm>
#include <cmath>

#include "core/pdsm/refined_pixel.h"
#include "core/util/png_writer.h"

namespace pdsm {
namespace {

int CeilDiv(int a, int b) { return (a + b - 1) / b; }

}  // namespace

PreviewImage::PreviewImage(int map_width, int map_height)
    : map_width_(map_width),
      map_height_(map_height),
      stride_(std::max(1, CeilDiv(std::max(map_width, map_height), kMaxPreviewSide))),
      width_(CeilDiv(map_width, stride_)),
      height_(CeilDiv(map_height, stride_)),
      rgb_(static_cast<size_t>(width_) * height_ * 3, 0) {}

bool PreviewImage::SampledColumn(int x) const {
  return x == std::min((x / stride_) * stride_ + stride_ / 2, map_width_ - 1);
}

bool PreviewImage::SampledRow(int y) const {
  return y == std::min((y / stride_) * stride_ + stride_ / 2, map_height_ - 1);
}

std::vector<float> PreviewImage::SampledDepths(int x0, int y0, int width, int height,
                                               std::span<const float> depth) const {
  std::vector<float> sampled;
  for (int j = 0; j < height; ++j) {
    if (!SampledRow(y0 + j)) continue;
    for (int i = 0; i < width; ++i) {
      if (SampledColumn(x0 + i)) sampled.push_back(depth[static_cast<size_t>(j) * width + i]);
    }
  }
  return sampled;
}

void PreviewImage::ShadeTile(const PdsmTile& tile, std::span<const float> sampled_depth) {
  size_t next = 0;
  for (int j = 0; j < tile.height; ++j) {
    if (!SampledRow(tile.y0 + j)) continue;
    for (int i = 0; i < tile.width; ++i) {
      if (!SampledColumn(tile.x0 + i)) continue;
      const float z = sampled_depth[next++];
      uint8_t rgb[3] = {24, 28, 52};
      if (std::isfinite(z)) {
        const double lit = 1.0 - EvaluatePixelCentre(tile.Function(i, j), z);
        const auto gray = static_cast<uint8_t>(std::lround(36 + 219 * lit));
        rgb[0] = rgb[1] = rgb[2] = gray;
      }
      // u x v = n points away from a viewer at the light, so u runs right-to-left on screen.
      const int column = width_ - 1 - (tile.x0 + i) / stride_;
      const int row = height_ - 1 - (tile.y0 + j) / stride_;
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
