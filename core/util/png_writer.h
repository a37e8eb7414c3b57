// Writing 8-bit RGB PNG images (previews, plots), via libpng.
#ifndef PDSM_CORE_UTIL_PNG_WRITER_H_
#define PDSM_CORE_UTIL_PNG_WRITER_H_

#include <cstdint>
#include <string>
#include <vector>

#include "absl/status/status.h"

namespace pdsm {

// `rgb` holds width * height * 3 bytes, row 0 at the top of the image.
absl::Status WriteRgbPng(const std::string& path, int width, int height,
                         const std::vector<uint8_t>& rgb);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_PNG_WRITER_H_
