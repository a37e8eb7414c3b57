#include "core/pdsm/refined_pixel.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

namespace pdsm {
namespace {

using ::testing::HasSubstr;

constexpr float kNaN = std::numeric_limits<float>::quiet_NaN();
const std::vector<Vertex> kOwn = {{0.5f, 0.0f}, {3.0f, 0.75f}};
const std::vector<RefinedBand> kEverywhere = {{-1e30f, 1e30f}};

// f * f sub-functions, sub-function k with k % 3 vertices (some empty).
std::vector<std::vector<Vertex>> Subs(int f) {
  std::vector<std::vector<Vertex>> subs(static_cast<size_t>(f) * f);
  for (size_t k = 0; k < subs.size(); ++k) {
    for (size_t n = 0; n < k % 3; ++n) {
      subs[k].push_back({1.0f + n, 0.1f * static_cast<float>(k % 10)});
    }
  }
  return subs;
}

TEST(RefinedPixel, SubFunctionsComeBackInRowMajorOrder) {
  for (int f : {2, 4, 8}) {
    const std::vector<std::vector<Vertex>> subs = Subs(f);
    std::vector<Vertex> pixel = {{7.0f, 0.5f}};  // another pixel's vertex before it
    AppendRefinedPixel(f, kEverywhere, kOwn, subs, &pixel);
    const std::span<const Vertex> samples = std::span<const Vertex>(pixel).subspan(1);
    EXPECT_EQ(RefinementOf(samples), f);
    EXPECT_EQ(PixelFunctionFault(samples, 8), "");
    const std::span<const Vertex> own = OwnFunction(samples);
    EXPECT_TRUE(std::equal(own.begin(), own.end(), kOwn.begin(), kOwn.end()));
    for (int j = 0; j < f; ++j) {
      for (int i = 0; i < f; ++i) {
        const std::span<const Vertex> got = SubFunction(samples, f, i, j);
        const std::vector<Vertex>& want = subs[static_cast<size_t>(i) + f * j];
        EXPECT_TRUE(std::equal(got.begin(), got.end(), want.begin(), want.end()))
            << f << ": " << i << "," << j;
      }
    }
  }
  const std::vector<Vertex> ordinary = {{1.0f, 0.0f}, {1.0f, 0.5f}};
  EXPECT_EQ(RefinementOf(ordinary), 1);
  EXPECT_EQ(RefinementOf({}), 1);
  EXPECT_EQ(OwnFunction(ordinary).data(), ordinary.data());
}

TEST(RefinedPixel, TheCentreIsTheMeanOfTheFourCentralSubPixels) {
  std::vector<std::vector<Vertex>> subs(16);
  for (int k = 0; k < 16; ++k) subs[k] = {{1.0f, 0.0f}, {1.0f, 0.05f * k}};
  std::vector<Vertex> pixel;
  AppendRefinedPixel(4, kEverywhere, kOwn, subs, &pixel);
  // Sub-pixels (1, 1), (2, 1), (1, 2), (2, 2): k = 5, 6, 9, 10.
  const double mean = 0.25 * (static_cast<double>(0.05f * 5) + 0.05f * 6 + 0.05f * 9 + 0.05f * 10);
  EXPECT_NEAR(EvaluatePixelCentre(pixel, 2.0), mean, 1e-12);
  EXPECT_EQ(EvaluatePixelCentre(pixel, 0.5), 0.0);
  const std::vector<Vertex> ordinary = {{1.0f, 0.0f}, {1.0f, 0.5f}};
  EXPECT_EQ(EvaluatePixelCentre(ordinary, 2.0), EvaluateAttenuation(ordinary, 2.0));
}

// Sub-functions defined on a band [2, 4) (NaN-bracketed), the last one empty (defined nowhere):
// inside the band a sub-pixel reads its sub-function and the centre their mean, the empty one
// counting with the pixel's own function; outside it every sub-pixel is undefined and the
// centre reads the pixel's own function.
TEST(RefinedPixel, OffItsWindowsAPixelReadsItsOwnFunction) {
  std::vector<std::vector<Vertex>> subs(4);
  for (int k = 0; k < 3; ++k) {
    const float a = 0.2f * (k + 1);
    subs[k] = {{kUndefinedFrom, kNaN}, {2.0f, a}, {4.0f, a}, {4.0f, kNaN}};
  }
  std::vector<Vertex> pixel;
  const std::vector<RefinedBand> band = {{2.0f, 4.0f}};
  AppendRefinedPixel(2, band, kOwn, subs, &pixel);
  ASSERT_EQ(PixelFunctionFault(pixel, 2), "");
  for (const double z : {1.0, 1.999, 4.001, 5.0}) {
    EXPECT_FALSE(RefinedAt(pixel, z)) << z;
    EXPECT_EQ(EvaluatePixelCentre(pixel, z), EvaluateAttenuation(kOwn, z)) << z;
    for (int k = 0; k < 4; ++k) {
      EXPECT_TRUE(std::isnan(SubPixelAttenuation(pixel, 2, k % 2, k / 2, z))) << z;
    }
  }
  for (const double z : {2.0, 3.0, 3.999}) {
    EXPECT_TRUE(RefinedAt(pixel, z)) << z;
    for (int k = 0; k < 3; ++k) {
      EXPECT_EQ(SubPixelAttenuation(pixel, 2, k % 2, k / 2, z), 0.2f * (k + 1)) << z;
    }
    EXPECT_TRUE(std::isnan(SubPixelAttenuation(pixel, 2, 1, 1, z)));
    EXPECT_NEAR(EvaluatePixelCentre(pixel, z),
                0.25 * (0.2f + 0.4f + 0.6f + EvaluateAttenuation(kOwn, z)), 1e-7);
  }
}

TEST(RefinedPixel, FaultsNameWhatIsWrong) {
  std::vector<Vertex> four;
  AppendRefinedPixel(4, kEverywhere, kOwn, Subs(4), &four);
  EXPECT_THAT(PixelFunctionFault(four, 2), HasSubstr("a refinement of 4"));
  // Without refinement (files before version 3) a pixel is an ordinary function: the marker's
  // depth 16 then the ends' smaller depths decrease.
  EXPECT_THAT(PixelFunctionFault(four, 1), HasSubstr("not nondecreasing"));
  std::vector<Vertex> three = four;
  three[0].a = -3.0f;
  EXPECT_THAT(PixelFunctionFault(three, 8), HasSubstr("a refinement of 3"));
  std::vector<Vertex> swapped = four;
  std::swap(swapped[6], swapped[7]);  // ends out of order
  EXPECT_THAT(PixelFunctionFault(swapped, 8), HasSubstr("not in order"));
  std::vector<Vertex> truncated = four;
  truncated.pop_back();  // the last end now lies past the vertices
  EXPECT_NE(PixelFunctionFault(truncated, 8), "");
  std::vector<Vertex> extra = four;
  extra.push_back({9.0f, 0.5f});  // a vertex no function owns
  EXPECT_THAT(PixelFunctionFault(extra, 8), HasSubstr("end at vertex"));
  const std::vector<Vertex> decreasing = {{2.0f, 0.5f}, {1.0f, 0.5f}};
  std::vector<std::vector<Vertex>> unordered(4, decreasing);
  std::vector<Vertex> bad;
  AppendRefinedPixel(2, kEverywhere, kOwn, unordered, &bad);
  EXPECT_THAT(PixelFunctionFault(bad, 2), HasSubstr("sub-pixel (0, 0)"));
  std::vector<Vertex> bad_own;
  AppendRefinedPixel(2, kEverywhere, decreasing, Subs(2), &bad_own);
  EXPECT_THAT(PixelFunctionFault(bad_own, 2), HasSubstr("its own function"));
}

}  // namespace
}  // namespace pdsm
