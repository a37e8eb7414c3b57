#include "core/util/png_writer.h"

#include <png.h>

#include "absl/strings/str_cat.h"
#include "core/util/atomic_file.h"

namespace pdsm {
namespace {

// libpng's write callback: appends to the std::string behind the io pointer.
void AppendToString(png_structp png, png_bytep data, png_size_t size) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), size);
}

void NoFlush(png_structp) {}

// `channels` bytes a pixel: 1 gray, 2 gray + alpha, 3 RGB, 4 RGBA.
absl::StatusOr<std::string> EncodeImpl(int width, int height, int channels, const char* what,
                                       const std::vector<uint8_t>& pixels) {
  static constexpr int kColorType[] = {PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA,
                                       PNG_COLOR_TYPE_RGB, PNG_COLOR_TYPE_RGB_ALPHA};
  if (channels < 1 || channels > 4) {
    return absl::InvalidArgumentError(absl::StrCat("PNG: ", channels, " channels (1 to 4)"));
  }
  const size_t row_bytes = static_cast<size_t>(width) * channels;
  if (width <= 0 || height <= 0 || pixels.size() != row_bytes * height) {
    return absl::InvalidArgumentError(absl::StrCat("PNG: ", width, "x", height, " ", what,
                                                   " pixels need ", row_bytes * height,
                                                   " bytes, got ", pixels.size()));
  }
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_write_struct(&png, &info);
    return absl::InternalError("libpng: cannot allocate");
  }
  std::string bytes;
  if (setjmp(png_jmpbuf(png))) {  // libpng reports errors by longjmp
    png_destroy_write_struct(&png, &info);
    return absl::InternalError("libpng: cannot encode the image");
  }
  png_set_write_fn(png, &bytes, &AppendToString, &NoFlush);
  png_set_IHDR(png, info, width, height, 8, kColorType[channels - 1], PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < height; ++y) {
    png_write_row(png, const_cast<png_bytep>(pixels.data() + static_cast<size_t>(y) * row_bytes));
  }
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return bytes;
}

absl::Status WriteEncoded(const std::string& path, const absl::StatusOr<std::string>& bytes,
                          FileSystem* fs) {
  if (!bytes.ok()) {
    return absl::Status(bytes.status().code(), absl::StrCat(path, ": ", bytes.status().message()));
  }
  return WriteFileAtomically(path, *bytes, fs);
}

}  // namespace

absl::StatusOr<std::string> EncodeRgbPng(int width, int height, const std::vector<uint8_t>& rgb) {
  return EncodeImpl(width, height, 3, "RGB", rgb);
}

absl::StatusOr<std::string> EncodeGrayAlphaPng(int width, int height,
                                               const std::vector<uint8_t>& gray_alpha) {
  return EncodeImpl(width, height, 2, "gray+alpha", gray_alpha);
}

absl::Status WriteGrayAlphaPng(const std::string& path, int width, int height,
                               const std::vector<uint8_t>& gray_alpha, FileSystem* fs) {
  return WriteEncoded(path, EncodeGrayAlphaPng(width, height, gray_alpha), fs);
}

absl::StatusOr<std::string> EncodePng(int width, int height, int channels,
                                      const std::vector<uint8_t>& pixels) {
  static constexpr const char* kWhat[] = {"gray", "gray+alpha", "RGB", "RGBA"};
  return EncodeImpl(width, height, channels,
                    channels >= 1 && channels <= 4 ? kWhat[channels - 1] : "?", pixels);
}

absl::Status WritePng(const std::string& path, int width, int height, int channels,
                      const std::vector<uint8_t>& pixels, FileSystem* fs) {
  return WriteEncoded(path, EncodePng(width, height, channels, pixels), fs);
}

absl::Status WriteRgbPng(const std::string& path, int width, int height,
                         const std::vector<uint8_t>& rgb, FileSystem* fs) {
  return WriteEncoded(path, EncodeRgbPng(width, height, rgb), fs);
}

}  // namespace pdsm
