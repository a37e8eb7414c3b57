#include "core/util/png_writer.h"

#include <gtest/gtest.h>
#include <png.h>

#include <cstring>
#include <string>
#include <vector>

#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

std::vector<uint8_t> Gradient(int width, int height, int seed) {
  std::vector<uint8_t> rgb(static_cast<size_t>(width) * height * 3);
  for (size_t i = 0; i < rgb.size(); ++i) rgb[i] = static_cast<uint8_t>(i * 7 + seed);
  return rgb;
}

// What libpng reads back from `bytes`.
std::vector<uint8_t> Decode(const std::string& bytes, int* width, int* height) {
  png_image image;
  std::memset(&image, 0, sizeof(image));
  image.version = PNG_IMAGE_VERSION;
  if (!png_image_begin_read_from_memory(&image, bytes.data(), bytes.size())) return {};
  image.format = PNG_FORMAT_RGB;
  std::vector<uint8_t> rgb(PNG_IMAGE_SIZE(image));
  if (!png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr)) return {};
  *width = static_cast<int>(image.width);
  *height = static_cast<int>(image.height);
  return rgb;
}

TEST(PngWriter, EncodesWhatLibpngDecodes) {
  const std::vector<uint8_t> rgb = Gradient(7, 3, 1);
  absl::StatusOr<std::string> bytes = EncodeRgbPng(7, 3, rgb);
  ASSERT_TRUE(bytes.ok()) << bytes.status();
  int width = 0, height = 0;
  EXPECT_EQ(Decode(*bytes, &width, &height), rgb);
  EXPECT_EQ(width, 7);
  EXPECT_EQ(height, 3);
}

TEST(PngWriter, WrongBufferSizeIsInvalidArgumentAndWritesNothing) {
  testing::TempDir dir;
  const absl::Status s = WriteRgbPng(dir.File("a.png"), 4, 4, std::vector<uint8_t>(47));
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(PngWriter, WritesTheEncodedBytes) {
  testing::TempDir dir;
  const std::vector<uint8_t> rgb = Gradient(5, 4, 2);
  ASSERT_TRUE(WriteRgbPng(dir.File("a.png"), 5, 4, rgb).ok());
  EXPECT_EQ(testing::ReadBytes(dir.File("a.png")), EncodeRgbPng(5, 4, rgb).value());
}

TEST(PngWriter, EveryFailureLeavesThePreviousImage) {
  testing::TempDir dir;
  const std::string path = dir.File("preview.png");
  ASSERT_TRUE(WriteRgbPng(path, 8, 8, Gradient(8, 8, 3)).ok());
  const std::vector<uint8_t> next = Gradient(64, 32, 4);
  testing::ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return WriteRgbPng(path, 64, 32, next, fs); });
}

}  // namespace
}  // namespace pdsm
