// Reading PNG images (alpha-mask textures: core/scene/alpha_mask.h), via libpng's simplified
// API. Any PNG libpng reads (gray, RGB, palette, 8 or 16 bits, with or without alpha) comes out
// as 8-bit gray + alpha.
#ifndef PDSM_CORE_UTIL_PNG_READER_H_
#define PDSM_CORE_UTIL_PNG_READER_H_

#include <cstdint>
#include <string_view>
#include <vector>

#include "absl/status/statusor.h"

namespace pdsm {

struct GrayAlphaImage {
  int width = 0, height = 0;
  // width * height pairs (gray, alpha), row 0 the image's top row. Colour becomes gray by
  // libpng's luminance weights; 16-bit channels are rounded to 8 bits; an image without an
  // alpha channel has alpha 255 everywhere (has_alpha false).
  std::vector<uint8_t> gray_alpha;
  bool has_alpha = false;
};

// Decodes the PNG file held in `bytes`. Images over `max_side` texels a side are refused before
// their pixels are allocated. INVALID_ARGUMENT (libpng's reason) for bytes that are not a PNG
// libpng can read, or an image too large.
absl::StatusOr<GrayAlphaImage> DecodePngGrayAlpha(std::string_view bytes, int max_side);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_PNG_READER_H_
