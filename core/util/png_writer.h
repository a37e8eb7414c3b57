// Writing 8-bit PNG images (previews, plots, screenshots, exports), via libpng.
#ifndef PDSM_CORE_UTIL_PNG_WRITER_H_
#define PDSM_CORE_UTIL_PNG_WRITER_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/util/file_system.h"

namespace pdsm {

// The PNG file's bytes. `rgb` holds width * height * 3 bytes, row 0 at the top of the image.
// INVALID_ARGUMENT when it does not; INTERNAL when libpng fails.
absl::StatusOr<std::string> EncodeRgbPng(int width, int height, const std::vector<uint8_t>& rgb);

// The same for gray + alpha pixels: width * height * 2 bytes (gray, then alpha: 0 transparent).
absl::StatusOr<std::string> EncodeGrayAlphaPng(int width, int height,
                                               const std::vector<uint8_t>& gray_alpha);

// The same for `channels` bytes a pixel: 1 gray, 2 gray + alpha, 3 RGB, 4 RGBA (alpha 0:
// transparent). INVALID_ARGUMENT for another count.
absl::StatusOr<std::string> EncodePng(int width, int height, int channels,
                                      const std::vector<uint8_t>& pixels);

// Encodes, then writes `path` through WriteFileAtomically (core/util/atomic_file.h): on any
// failure `path` is left as it was and no temporary file remains. `fs` null means
// FileSystem::Default().
absl::Status WriteRgbPng(const std::string& path, int width, int height,
                         const std::vector<uint8_t>& rgb, FileSystem* fs = nullptr);
absl::Status WriteGrayAlphaPng(const std::string& path, int width, int height,
                               const std::vector<uint8_t>& gray_alpha, FileSystem* fs = nullptr);
absl::Status WritePng(const std::string& path, int width, int height, int channels,
                      const std::vector<uint8_t>& pixels, FileSystem* fs = nullptr);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_PNG_WRITER_H_
