// Where a bake's error lives (client/measure/error_map.h, `pdsm compare`): each pixel of the map
// must hold `pdsm query` and the exact reference at the receiver point its ray meets (on the
// ray, and on the ground recomputed here from the file's geometry), its statistics
// must be those of its pixels, a coarser step must pick the same rays, a worse bake must show
// more error where the penumbra is, and the PNG must draw the map in the legend's colours.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "client/measure/error_map.h"
#include "client/view/image_io.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/reference/exact_visibility.h"
#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm::testing {
namespace {

const std::string kPdsm = PDSM_CLI;

// plates at 64² with `samples` light samples, baked into dir/NAME.exr and read back.
PdsmImage BakePlates(const TempDir& dir, const std::string& name, int samples, Scene* scene) {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(64);
  overrides.add_resolution(64);
  overrides.set_samples(samples);
  overrides.set_shadow_map_resolution(256);
  absl::StatusOr<Scene> loaded = LoadSceneFile(ExamplePath("plates"), overrides);
  EXPECT_TRUE(loaded.ok()) << loaded.status();
  *scene = *loaded;
  LocalBakeOptions options;
  options.output_path = dir.File(name + ".exr");
  options.threads = 2;
  absl::StatusOr<BakeSummary> summary = RunLocalBake(*scene, options);
  EXPECT_TRUE(summary.ok()) << summary.status();
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(options.output_path);
  EXPECT_TRUE(pdsm.ok()) << pdsm.status();
  return *std::move(pdsm);
}

class ErrorMapTest : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    dir_ = new TempDir();
    scene_ = new Scene();
    pdsm_ = new PdsmImage(BakePlates(*dir_, "plates64", 64, scene_));
  }
  static void TearDownTestSuite() {
    delete pdsm_;
    delete scene_;
    delete dir_;
  }
  static TempDir* dir_;
  static Scene* scene_;
  static PdsmImage* pdsm_;
};
TempDir* ErrorMapTest::dir_ = nullptr;
Scene* ErrorMapTest::scene_ = nullptr;
PdsmImage* ErrorMapTest::pdsm_ = nullptr;

TEST_F(ErrorMapTest, PixelsHoldTheQueryAndTheExactReferenceAtTheirReceiverPoint) {
  absl::StatusOr<ErrorMap> map =
      MeasureErrorMap(*pdsm_, *scene_, ReferenceOptions{ReferenceMethod::kAuto}, 1);
  ASSERT_TRUE(map.ok()) << map.status();
  const PdsmGeometry& g = pdsm_->header.geometry;
  ASSERT_EQ(map->width, g.width);
  ASSERT_EQ(map->height, g.height);
  EXPECT_EQ(map->method, ReferenceMethod::kExact);  // plates has a rect light
  // Each defined pixel's point must be on its ray (from the light's centre through the PDSM
  // pixel's window centre): on the ground y = 0 where nothing receives first, recomputed here.
  std::vector<glm::dvec3> points;
  std::vector<size_t> pixels;
  int defined = 0, on_ground = 0;
  const glm::dvec3 origin = g.frame.WorldFromLight(glm::dvec3(0.0));
  for (int r = 0; r < map->height; r += 3) {
    for (int c = 0; c < map->width; c += 3) {
      const size_t p = static_cast<size_t>(r) * map->width + c;
      if (std::isnan(map->pdsm[p])) continue;
      ++defined;
      // Image pixel (c, r) is PDSM pixel (w-1-c, h-1-r).
      const double s = g.PixelCenterS(g.width - 1 - c), t = g.PixelCenterT(g.height - 1 - r);
      const glm::dvec3 direction =
          glm::normalize(g.frame.WorldFromLight(glm::dvec3(s, t, 1.0)) - origin);
      const glm::dvec3 to_point = map->point[p] - origin;
      EXPECT_LT(glm::length(to_point - direction * glm::dot(to_point, direction)), 1e-4)
          << "pixel " << c << "," << r << " off its ray";
      glm::dvec3 point = map->point[p];
      if (std::abs(point.y) < 1e-3) {
        ++on_ground;
        point = origin + direction * (-origin.y / direction.y);
        EXPECT_LT(glm::length(point - map->point[p]), 1e-4);
      }
      points.push_back(point);
      pixels.push_back(p);
    }
  }
  EXPECT_GT(defined, 22 * 22 * 9 / 10);
  EXPECT_GT(on_ground, defined / 2);
  EXPECT_LT(on_ground, defined);  // some rays meet a plate first: it receives too
  absl::StatusOr<std::vector<double>> exact = ExactAttenuation(*scene_, points);
  ASSERT_TRUE(exact.ok()) << exact.status();
  int penumbra = 0;
  for (size_t k = 0; k < points.size(); ++k) {
    const size_t p = pixels[k];
    // Floats: the map stores both values as float and its depth came through a float ray.
    EXPECT_NEAR(map->reference[p], (*exact)[k], 2e-4) << k;
    EXPECT_NEAR(map->pdsm[p], QueryAttenuation(*pdsm_, points[k]), 2e-4) << k;
    penumbra += (*exact)[k] > 0 && (*exact)[k] < 1;
  }
  EXPECT_GT(penumbra, 10);  // the check saw penumbra, not only lit ground and umbra
}

TEST_F(ErrorMapTest, SummaryIsThatOfItsPixelsAndACoarserStepPicksTheSameRays) {
  absl::StatusOr<ErrorMap> fine =
      MeasureErrorMap(*pdsm_, *scene_, ReferenceOptions{ReferenceMethod::kExact}, 1);
  absl::StatusOr<ErrorMap> coarse =
      MeasureErrorMap(*pdsm_, *scene_, ReferenceOptions{ReferenceMethod::kExact}, 3);
  ASSERT_TRUE(fine.ok() && coarse.ok());
  ASSERT_EQ(coarse->width, 22);  // ceil(64 / 3)
  ASSERT_EQ(coarse->height, 22);
  for (int r = 0; r < coarse->height; ++r) {
    for (int c = 0; c < coarse->width; ++c) {
      const size_t p = static_cast<size_t>(r) * coarse->width + c;
      const size_t q = static_cast<size_t>(3 * r) * fine->width + 3 * c;
      EXPECT_EQ(coarse->pdsm[p], fine->pdsm[q]);
      EXPECT_EQ(coarse->reference[p], fine->reference[q]);
    }
  }
  const ErrorMapSummary summary = SummarizeErrorMap(*fine);
  std::vector<double> all, penumbra;
  for (size_t p = 0; p < fine->pdsm.size(); ++p) {
    const double e = std::abs(double(fine->pdsm[p]) - double(fine->reference[p]));
    all.push_back(e);
    if (fine->reference[p] > 0 && fine->reference[p] < 1) penumbra.push_back(e);
  }
  ASSERT_EQ(summary.all.count, all.size());
  ASSERT_EQ(summary.penumbra.count, penumbra.size());
  ASSERT_GT(penumbra.size(), 100u);
  ASSERT_LT(penumbra.size(), all.size());
  double sum = 0;
  for (double e : all) sum += e;
  EXPECT_NEAR(summary.all.mean, sum / all.size(), 1e-9);
  std::sort(all.begin(), all.end());
  EXPECT_EQ(summary.all.max, all.back());
  EXPECT_LE(summary.all.p95, summary.all.p99);
  EXPECT_LE(summary.all.p99, summary.all.max);
  // 99% of the pixels are at or below P99, and fewer than 99% below it.
  const auto below = [&](double v) {
    return std::count_if(all.begin(), all.end(), [&](double e) { return e < v; });
  };
  EXPECT_GE(std::upper_bound(all.begin(), all.end(), summary.all.p99) - all.begin(),
            static_cast<long>(std::ceil(0.99 * all.size())));
  EXPECT_LT(below(summary.all.p99), static_cast<long>(std::ceil(0.99 * all.size())));
  // The penumbra is where a 64-sample bake's error is: its mean there exceeds the overall one.
  EXPECT_GT(summary.penumbra.mean, summary.all.mean);
}

TEST_F(ErrorMapTest, FewerSamplesShowMoreErrorInThePenumbra) {
  Scene scene4;
  const PdsmImage pdsm4 = BakePlates(*dir_, "plates4", 4, &scene4);
  absl::StatusOr<ErrorMap> map64 = MeasureErrorMap(*pdsm_, *scene_, ReferenceOptions{}, 1);
  absl::StatusOr<ErrorMap> map4 = MeasureErrorMap(pdsm4, scene4, ReferenceOptions{}, 1);
  ASSERT_TRUE(map64.ok() && map4.ok());
  const ErrorMapSummary s64 = SummarizeErrorMap(*map64), s4 = SummarizeErrorMap(*map4);
  // The same rays and receivers: the same reference and the same penumbra pixels.
  EXPECT_EQ(map64->reference, map4->reference);
  EXPECT_EQ(s64.penumbra.count, s4.penumbra.count);
  EXPECT_GT(s4.penumbra.mean, 2 * s64.penumbra.mean);
  EXPECT_GT(s4.penumbra.p99, s64.penumbra.p99);
}

// The picture: the map's pixels in the scale's colours, magnified, above the legend.
TEST_F(ErrorMapTest, CompareCommandDrawsTheMapInTheScalesColours) {
  const std::string png = dir_->File("error.png");
  const CommandResult r =
      RunCommand(kPdsm + " compare " + dir_->File("plates64.exr") + " --scene " +
                     ExamplePath("plates") + " -o " + png + " --max-error 0.05",
                 *dir_);
  // The command baked nothing: plates' own knobs differ from this file's, and the header check
  // compares the light and scene, not the knobs.
  ASSERT_EQ(r.exit_code, 0) << r.err;
  absl::StatusOr<ErrorMap> map = MeasureErrorMap(*pdsm_, *scene_, ReferenceOptions{}, 1);
  ASSERT_TRUE(map.ok());
  const ErrorMapSummary summary = SummarizeErrorMap(*map);
  EXPECT_NE(r.out.find("all       " + FormatErrorStats(summary.all)), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("penumbra  " + FormatErrorStats(summary.penumbra)), std::string::npos)
      << r.out;
  absl::StatusOr<view::RgbImage> image = view::ReadPng(png);
  ASSERT_TRUE(image.ok()) << image.status();
  const int zoom = 512 / 64;
  ASSERT_EQ(image->width, 64 * zoom);
  ASSERT_GT(image->height, 64 * zoom + 40);  // the legend below
  int checked = 0;
  for (int r = 0; r < map->height; r += 5) {
    for (int c = 0; c < map->width; c += 5) {
      const size_t p = static_cast<size_t>(r) * map->width + c;
      unsigned char want[3];
      ErrorColour(map->Error(p), 0.05, want);
      const uint8_t* got = &image->rgb[(static_cast<size_t>(r * zoom + zoom / 2) * image->width +
                                        c * zoom + zoom / 2) *
                                       3];
      EXPECT_EQ(got[0], want[0]) << c << "," << r;
      EXPECT_EQ(got[1], want[1]) << c << "," << r;
      EXPECT_EQ(got[2], want[2]) << c << "," << r;
      ++checked;
    }
  }
  EXPECT_EQ(checked, 13 * 13);
}

// A lone tilted quad under a rect light: nothing shadows it, so the exact answer is 0 on all of
// it. Its points lie on its plane only within rounding; without the nudge toward the light, the
// reference read 1 wherever rounding put a point behind the plane (half of them, on the dragon).
TEST(ErrorMapTilted, AReceiverNeverHidesItselfFromTheReference) {
  TempDir dir;
  WriteText(dir.File("tilted.json"), R"({"name": "tilted", "meshes": [
    {"inline": {"positions": [-3,0.3,-3, 3,-1.7,-3, 3,-1.7,3, -3,0.3,3], "indices": [0,1,2, 0,2,3]}}],
    "light": {"rect": {"center": [0.3,6,0.2], "normal": [0,-1,0], "up": [0,0,1], "size": [1,1]}},
    "bake": {"resolution": [48,48], "samples": 4}})");
  absl::StatusOr<Scene> scene = LoadSceneFile(dir.File("tilted.json"));
  ASSERT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions options;
  options.output_path = dir.File("tilted.exr");
  ASSERT_TRUE(RunLocalBake(*scene, options).ok());
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(options.output_path);
  ASSERT_TRUE(pdsm.ok()) << pdsm.status();
  absl::StatusOr<ErrorMap> map = MeasureErrorMap(*pdsm, *scene, ReferenceOptions{}, 1);
  ASSERT_TRUE(map.ok()) << map.status();
  const ErrorMapSummary summary = SummarizeErrorMap(*map);
  EXPECT_GT(summary.all.count, 48u * 48u / 2);
  for (size_t p = 0; p < map->reference.size(); ++p) {
    if (!std::isnan(map->reference[p])) {
      EXPECT_EQ(map->reference[p], 0.0f) << p;
    }
  }
  EXPECT_EQ(summary.all.max, 0.0);
}

TEST(ErrorColour, RunsFromPurpleToYellowAndGreyMeansNoValue) {
  unsigned char low[3], high[3], above[3], none[3], mid[3];
  ErrorColour(0.0, 0.1, low);
  ErrorColour(0.1, 0.1, high);
  ErrorColour(5.0, 0.1, above);
  ErrorColour(0.05, 0.1, mid);
  ErrorColour(std::nan(""), 0.1, none);
  EXPECT_EQ(std::vector<int>(low, low + 3), (std::vector<int>{68, 1, 84}));
  EXPECT_EQ(std::vector<int>(high, high + 3), (std::vector<int>{253, 231, 37}));
  EXPECT_EQ(std::vector<int>(above, above + 3), std::vector<int>(high, high + 3));
  EXPECT_EQ(std::vector<int>(mid, mid + 3), (std::vector<int>{33, 144, 141}));
  EXPECT_EQ(std::vector<int>(none, none + 3),
            (std::vector<int>{kNoValueGrey, kNoValueGrey, kNoValueGrey}));
  // Brighter as the error grows (viridis' lightness is monotonic).
  int previous = -1;
  for (int k = 0; k <= 20; ++k) {
    unsigned char rgb[3];
    ErrorColour(0.005 * k, 0.1, rgb);
    const int luma = 299 * rgb[0] + 587 * rgb[1] + 114 * rgb[2];
    EXPECT_GT(luma, previous) << k;
    previous = luma;
  }
}

TEST(CompareCli, RefusesWhatItCannotCompare) {
  TempDir dir;
  WriteText(dir.File("tiny.json"), kTinySceneJson);
  CommandResult r = RunCommand(
      kPdsm + " bake " + dir.File("tiny.json") + " -o " + dir.File("tiny.exr") + " --no-preview",
      dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  // Another scene than the bake's: its header names the mismatch.
  r = RunCommand(kPdsm + " compare " + dir.File("tiny.exr") + " --scene " + ExamplePath("plates") +
                     " -o " + dir.File("e.png"),
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("scene_name"), std::string::npos) << r.err;
  // Not a PNG.
  r = RunCommand(kPdsm + " compare " + dir.File("tiny.exr") + " --scene " + dir.File("tiny.json") +
                     " -o " + dir.File("e.exr"),
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(".png"), std::string::npos) << r.err;
  // A step of 0, a negative scale.
  r = RunCommand(kPdsm + " compare " + dir.File("tiny.exr") + " --scene " + dir.File("tiny.json") +
                     " -o " + dir.File("e.png") + " --step 0",
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--step"), std::string::npos) << r.err;
  r = RunCommand(kPdsm + " compare " + dir.File("tiny.exr") + " --scene " + dir.File("tiny.json") +
                     " -o " + dir.File("e.png") + " --max-error -1",
                 dir);
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find("--max-error"), std::string::npos) << r.err;
  EXPECT_FALSE(std::filesystem::exists(dir.File("e.png")));
  EXPECT_FALSE(std::filesystem::exists(dir.File("e.exr")));
  // And the one that works: the tiny scene's map, 48x48 magnified by 10.
  r = RunCommand(kPdsm + " compare " + dir.File("tiny.exr") + " --scene " + dir.File("tiny.json") +
                     " -o " + dir.File("e.png") + " --step 2",
                 dir);
  ASSERT_EQ(r.exit_code, 0) << r.err;
  EXPECT_NE(r.out.find("24x24, |pdsm - exact| on the receivers, 1 of 2x2 pixels"),
            std::string::npos)
      << r.out;
  absl::StatusOr<view::RgbImage> image = view::ReadPng(dir.File("e.png"));
  ASSERT_TRUE(image.ok()) << image.status();
  EXPECT_EQ(image->width, 24 * 21);
}

}  // namespace
}  // namespace pdsm::testing
