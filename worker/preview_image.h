// The bake's preview: attenuation on the receivers as seen from the light's centre, one image
// pixel per PDSM pixel, oriented as a camera at the light looking along n with v up.
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

class PreviewImage {
 public:
  PreviewImage(int width, int height);

  // Shades the tile's pixels: lit receivers white, umbra dark, no receiver dark blue.
  // `receiver_depth` is row-major over the tile (+infinity where no receiver).
  // Thread-safe for distinct tiles.
  void ShadeTile(const PdsmTile& tile, std::span<const float> receiver_depth);

  // A PNG through WriteRgbPng (core/util/png_writer.h): `path` is replaced whole or left as it
  // was, with no temporary file left. `fs` null means FileSystem::Default().
  absl::Status Write(const std::string& path, FileSystem* fs = nullptr) const;

 private:
  int width_, height_;
  std::vector<uint8_t> rgb_;
};

}  // namespace pdsm

#endif  // PDSM_WORKER_PREVIEW_IMAGE_H_
