// The bake's preview: attenuation on the receivers as seen from the light's centre, oriented
// as a camera at the light looking along n with v up. One image pixel per PDSM pixel up to
// kMaxPreviewSide pixels a side; a larger map is shown one pixel per `stride` x `stride`
// block, the block's middle pixel standing for it (point sampling: a preview, not a filtered
// picture), so that a map of any size has a preview of bounded memory (issue #12 item 5).
#ifndef PDSM_WORKER_PREVIEW_IMAGE_H_
#define PDSM_WORKER_PREVIEW_IMAGE_H_

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "core/pdsm/pdsm_image.h"
#include "core/util/file_system.h"

namespace pdsm {

inline constexpr int kMaxPreviewSide = 4096;

class PreviewImage {
 public:
  // The preview of a map of `map_width` x `map_height` pixels.
  PreviewImage(int map_width, int map_height);

  int width() const { return width_; }
  int height() const { return height_; }
  // PDSM pixels a side of the block one preview pixel shows (1 up to kMaxPreviewSide).
  int stride() const { return stride_; }

  // The depths, of a tile at (x0, y0) of width x height pixels, that ShadeTile reads: those
  // of the pixels the preview samples, in row-major order. `depth` is row-major over the tile.
  std::vector<float> SampledDepths(int x0, int y0, int width, int height,
                                   std::span<const float> depth) const;

  // Shades the tile's sampled pixels: lit receivers white, umbra dark, no receiver dark blue.
  // `sampled_depth` is SampledDepths of the tile's receiver depths (+infinity where no
  // receiver). Thread-safe for distinct tiles.
  void ShadeTile(const PdsmTile& tile, std::span<const float> sampled_depth);

  // A PNG through WriteRgbPng (core/util/png_writer.h): `path` is replaced whole or left as it
  // was, with no temporary file left. `fs` null means FileSystem::Default().
  absl::Status Write(const std::string& path, FileSystem* fs = nullptr) const;

 private:
  // Whether the preview samples map column x (row y): the middle of its block, clipped to
  // the map for the last block.
  bool SampledColumn(int x) const;
  bool SampledRow(int y) const;

  int map_width_, map_height_;
  int stride_;
  int width_, height_;
  std::vector<uint8_t> rgb_;
};

}  // namespace pdsm

#endif  // PDSM_WORKER_PREVIEW_IMAGE_H_
