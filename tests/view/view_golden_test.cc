// Golden images of pdsm-view: every mode side by side on small bakes of the examples,
// compared with tests/golden/*.png. Regenerate (after a deliberate change, and look at the
// images) with:  PDSM_UPDATE_GOLDENS=1 build/tests/e2e_tests --gtest_filter='ViewGolden.*'
#include <algorithm>
#include <cstdlib>
#include <string>

#include <gtest/gtest.h>

#include "client/view/image_io.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

// Tolerance (docs/viewer.md): a pixel differs when a channel is off by more than 8/255; at
// most 0.5% of pixels may differ. Room for another Mesa/llvmpipe build rounding differently,
// not for a moved shadow.
constexpr int kChannelTolerance = 8;
constexpr double kMaxDifferingFraction = 0.005;

std::string GoldenPath(const std::string& name) {
  return std::string(PDSM_SOURCE_DIR) + "/tests/golden/" + name + ".png";
}

// Writes OUT_actual.png and OUT_diff.png (red: differing pixels over the dimmed golden).
void WriteFailureImages(const view::RgbImage& actual, const view::RgbImage& golden,
                        const std::string& name) {
  const std::string base = ViewTestOutputDir() + "/" + name;
  ASSERT_TRUE(view::WritePng(base + "_actual.png", actual).ok());
  view::RgbImage diff = actual;
  if (actual.width == golden.width && actual.height == golden.height) {
    for (size_t i = 0; i < diff.rgb.size(); i += 3) {
      int d = 0;
      for (int c = 0; c < 3; ++c) d = std::max(d, std::abs(actual.rgb[i + c] - golden.rgb[i + c]));
      const uint8_t dim = static_cast<uint8_t>(golden.rgb[i + 1] / 3);
      diff.rgb[i] = d > kChannelTolerance ? 255 : dim;
      diff.rgb[i + 1] = d > kChannelTolerance ? 0 : dim;
      diff.rgb[i + 2] = d > kChannelTolerance ? 0 : dim;
    }
  }
  ASSERT_TRUE(view::WritePng(base + "_diff.png", diff).ok());
  ADD_FAILURE() << "golden " << GoldenPath(name) << " differs; see " << base << "_actual.png and "
                << base << "_diff.png";
}

void ExpectMatchesGolden(const std::string& png, const std::string& name) {
  absl::StatusOr<view::RgbImage> actual = view::ReadPng(png);
  ASSERT_TRUE(actual.ok()) << actual.status();
  if (const char* update = std::getenv("PDSM_UPDATE_GOLDENS");
      update && std::string(update) == "1") {
    ASSERT_TRUE(view::WritePng(GoldenPath(name), *actual).ok());
    GTEST_SKIP() << "updated " << GoldenPath(name);
  }
  absl::StatusOr<view::RgbImage> golden = view::ReadPng(GoldenPath(name));
  ASSERT_TRUE(golden.ok()) << golden.status() << " (PDSM_UPDATE_GOLDENS=1 makes it)";
  if (golden->width != actual->width || golden->height != actual->height) {
    WriteFailureImages(*actual, *golden, name);
    return;
  }
  size_t differing = 0;
  for (size_t i = 0; i < actual->rgb.size(); i += 3) {
    for (int c = 0; c < 3; ++c) {
      if (std::abs(actual->rgb[i + c] - golden->rgb[i + c]) > kChannelTolerance) {
        ++differing;
        break;
      }
    }
  }
  const size_t pixels = actual->rgb.size() / 3;
  std::printf("%s: %zu of %zu pixels beyond %d/255\n", name.c_str(), differing, pixels,
              kChannelTolerance);
  if (differing > kMaxDifferingFraction * pixels) WriteFailureImages(*actual, *golden, name);
}

TEST(ViewGolden, PlatesEveryMode) {
  TempDir dir;
  const std::string png = dir.File("plates.png");
  CommandResult r =
      RunView("plates",
              "--pdsm " + SmallBake("plates") +
                  " --headless --size 160x120 --camera 4,7,6,0,1,0,40 --sphere 2,0.8,2.5,0.5"
                  " --compare pdsm,cpu,hard,pcf,pcss,vsm,multi-sm --screenshot " +
                  png,
              dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("pdsm,cpu,hard,pcf,pcss,vsm,multi-sm"), std::string::npos) << r.out;
  ExpectMatchesGolden(png, "view_plates_modes");
}

// The sun: orthographic PDSM and sheared orthographic shadow maps.
TEST(ViewGolden, SunPillarsPdsmHardMultiSm) {
  TempDir dir;
  const std::string png = dir.File("sun.png");
  CommandResult r = RunView("sun_pillars",
                            "--pdsm " + SmallBake("sun_pillars") +
                                " --headless --size 160x120 --compare pdsm,hard,multi-sm "
                                "--screenshot " +
                                png,
                            dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  ExpectMatchesGolden(png, "view_sun_pillars_modes");
}

}  // namespace
}  // namespace pdsm::testing
