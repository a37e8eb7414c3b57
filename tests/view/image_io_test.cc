// The viewer's image files (client/view/image_io.h): what is written reads back, and a write
// that fails at any step leaves the previous screenshot or PFM as it was.
#include "client/view/image_io.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <string>

#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm::testing {
namespace {

view::RgbImage Rgb(int width, int height, int seed) {
  view::RgbImage image{width, height, {}};
  image.rgb.resize(static_cast<size_t>(width) * height * 3);
  for (size_t i = 0; i < image.rgb.size(); ++i) image.rgb[i] = static_cast<uint8_t>(i * 5 + seed);
  return image;
}

view::FloatImage Floats(int width, int height, float scale) {
  view::FloatImage image{width, height, {}};
  for (int i = 0; i < width * height; ++i) image.values.push_back(scale * i);
  return image;
}

TEST(ImageIo, PngAndPfmRoundTrip) {
  TempDir dir;
  const view::RgbImage rgb = Rgb(9, 4, 1);
  ASSERT_TRUE(view::WritePng(dir.File("a.png"), rgb).ok());
  absl::StatusOr<view::RgbImage> png = view::ReadPng(dir.File("a.png"));
  ASSERT_TRUE(png.ok()) << png.status();
  EXPECT_EQ(png->width, 9);
  EXPECT_EQ(png->rgb, rgb.rgb);
  const view::FloatImage floats = Floats(5, 3, 0.25f);
  ASSERT_TRUE(view::WritePfm(dir.File("a.pfm"), floats).ok());
  absl::StatusOr<view::FloatImage> pfm = view::ReadPfm(dir.File("a.pfm"));
  ASSERT_TRUE(pfm.ok()) << pfm.status();
  EXPECT_EQ(pfm->values, floats.values);
  EXPECT_THAT(FilesUnder(dir.path()), ::testing::ElementsAre("a.pfm", "a.png"));
}

TEST(ImageIo, PfmOfTheWrongSizeIsRefused) {
  TempDir dir;
  view::FloatImage floats = Floats(5, 3, 1.0f);
  floats.values.pop_back();
  EXPECT_EQ(view::WritePfm(dir.File("a.pfm"), floats).code(), absl::StatusCode::kInvalidArgument);
  EXPECT_TRUE(std::filesystem::is_empty(dir.path()));
}

TEST(ImageIo, EveryFailureLeavesThePreviousScreenshot) {
  TempDir dir;
  const std::string path = dir.File("shot.png");
  ASSERT_TRUE(view::WritePng(path, Rgb(4, 4, 2)).ok());
  const view::RgbImage next = Rgb(32, 16, 3);
  ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return view::WritePng(path, next, fs); });
}

TEST(ImageIo, EveryFailureLeavesThePreviousPfm) {
  TempDir dir;
  const std::string path = dir.File("attenuation.pfm");
  ASSERT_TRUE(view::WritePfm(path, Floats(3, 3, 1.0f)).ok());
  const view::FloatImage next = Floats(40, 30, 0.5f);
  ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return view::WritePfm(path, next, fs); });
}

}  // namespace
}  // namespace pdsm::testing
