#include "client/view/image_io.h"

#include <png.h>

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "absl/strings/str_cat.h"
#include "core/util/atomic_file.h"
#include "core/util/png_writer.h"

namespace pdsm::view {

absl::Status WritePng(const std::string& path, const RgbImage& image, FileSystem* fs) {
  return WriteRgbPng(path, image.width, image.height, image.rgb, fs);
}

absl::StatusOr<RgbImage> ReadPng(const std::string& path) {
  if (!std::filesystem::exists(path))
    return absl::NotFoundError(absl::StrCat(path, ": no such file"));
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_file(&image, path.c_str())) {
    return absl::DataLossError(absl::StrCat(path, ": not a PNG (", image.message, ")"));
  }
  image.format = PNG_FORMAT_RGB;
  RgbImage out;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  out.rgb.resize(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, out.rgb.data(), 0, nullptr)) {
    png_image_free(&image);
    return absl::DataLossError(absl::StrCat(path, ": corrupt PNG (", image.message, ")"));
  }
  return out;
}

absl::Status WritePfm(const std::string& path, const FloatImage& image, FileSystem* fs) {
  if (image.width < 0 || image.height < 0 ||
      image.values.size() != static_cast<size_t>(image.width) * image.height) {
    return absl::InvalidArgumentError(absl::StrCat(path, ": a ", image.width, "x", image.height,
                                                   " PFM needs as many values, got ",
                                                   image.values.size()));
  }
  std::string bytes = absl::StrCat("Pf\n", image.width, " ", image.height, "\n-1.0\n");  // LE
  for (int y = image.height - 1; y >= 0; --y) {
    bytes.append(reinterpret_cast<const char*>(&image.values[static_cast<size_t>(y) * image.width]),
                 static_cast<size_t>(image.width) * sizeof(float));
  }
  return WriteFileAtomically(path, bytes, fs);
}

absl::StatusOr<FloatImage> ReadPfm(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return absl::NotFoundError(absl::StrCat(path, ": cannot open"));
  std::string magic;
  FloatImage image;
  double scale = 0;
  in >> magic >> image.width >> image.height >> scale;
  in.get();  // the one whitespace after the scale
  if (!in || magic != "Pf" || image.width <= 0 || image.height <= 0 || scale >= 0) {
    return absl::DataLossError(absl::StrCat(path, ": not a little-endian greyscale PFM"));
  }
  image.values.resize(static_cast<size_t>(image.width) * image.height);
  for (int y = image.height - 1; y >= 0; --y) {
    in.read(reinterpret_cast<char*>(&image.values[static_cast<size_t>(y) * image.width]),
            static_cast<std::streamsize>(image.width * sizeof(float)));
  }
  if (!in) return absl::DataLossError(absl::StrCat(path, ": truncated"));
  return image;
}

RgbImage Composite(const std::vector<RgbImage>& images, int columns, int gap) {
  const int w = images.front().width, h = images.front().height;
  const int n = static_cast<int>(images.size());
  columns = std::clamp(columns, 1, n);
  const int rows = (n + columns - 1) / columns;
  RgbImage out;
  out.width = columns * w + (columns - 1) * gap;
  out.height = rows * h + (rows - 1) * gap;
  out.rgb.assign(static_cast<size_t>(out.width) * out.height * 3, 16);
  for (int i = 0; i < n; ++i) {
    const int x0 = (i % columns) * (w + gap), y0 = (i / columns) * (h + gap);
    for (int y = 0; y < h; ++y) {
      std::memcpy(&out.rgb[(static_cast<size_t>(y0 + y) * out.width + x0) * 3],
                  &images[i].rgb[static_cast<size_t>(y) * w * 3], static_cast<size_t>(w) * 3);
    }
  }
  return out;
}

}  // namespace pdsm::view
