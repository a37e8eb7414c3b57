// Images the viewer writes and its tests read: 8-bit RGB PNG (screenshots, composites, diff
// images) and single-channel float32 PFM (the attenuation each pixel was shaded with). Writes
// go through WriteFileAtomically (core/util/atomic_file.h): a failed write leaves the target
// as it was and no temporary file. `fs` null means FileSystem::Default().
#ifndef PDSM_CLIENT_VIEW_IMAGE_IO_H_
#define PDSM_CLIENT_VIEW_IMAGE_IO_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/util/file_system.h"

namespace pdsm::view {

struct RgbImage {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // row 0 at the top
};

struct FloatImage {
  int width = 0, height = 0;
  std::vector<float> values;  // row 0 at the top
};

absl::Status WritePng(const std::string& path, const RgbImage& image, FileSystem* fs = nullptr);
// NOT_FOUND (no file), DATA_LOSS (not a PNG); any PNG is converted to 8-bit RGB.
absl::StatusOr<RgbImage> ReadPng(const std::string& path);

// PFM "Pf" (greyscale, little-endian, rows stored bottom to top as the format says).
// INVALID_ARGUMENT when `values` does not hold width * height floats.
absl::Status WritePfm(const std::string& path, const FloatImage& image, FileSystem* fs = nullptr);
absl::StatusOr<FloatImage> ReadPfm(const std::string& path);

// Tiles equally sized images left to right, `columns` per row (rows of tiles top to bottom),
// with a `gap`-pixel dark border between them. REQUIRES: images non-empty, same size.
RgbImage Composite(const std::vector<RgbImage>& images, int columns, int gap);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_IMAGE_IO_H_
