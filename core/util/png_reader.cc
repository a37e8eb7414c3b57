#include "core/util/png_reader.h"

#include <png.h>

#include <cstring>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace pdsm {

absl::StatusOr<GrayAlphaImage> DecodePngGrayAlpha(std::string_view bytes, int max_side) {
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  const auto failed = [&](const char* what) {
    absl::Status status = absl::InvalidArgumentError(absl::StrCat(what, ": ", image.message));
    png_image_free(&image);
    return status;
  };
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) {
    return failed("not a readable PNG");
  }
  if (image.width == 0 || image.height == 0 || image.width > static_cast<png_uint_32>(max_side) ||
      image.height > static_cast<png_uint_32>(max_side)) {
    const std::string size = absl::StrCat(image.width, "x", image.height);
    png_image_free(&image);
    return absl::InvalidArgumentError(
        absl::StrCat("the image is ", size, " texels; at most ", max_side, " a side are read"));
  }
  GrayAlphaImage out;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  out.has_alpha = (image.format & PNG_FORMAT_FLAG_ALPHA) != 0;
  // 8-bit, not premultiplied: alpha comes out as stored (PNG never gamma-encodes it), a gray
  // image's values as stored, colour through libpng's RGB-to-gray conversion.
  image.format = PNG_FORMAT_GA;
  out.gray_alpha.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.gray_alpha.data(), 0, nullptr)) {
    return failed("decoding the PNG failed");
  }
  return out;
}

}  // namespace pdsm
