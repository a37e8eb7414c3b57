#include "core/scene/alpha_mask.h"

#include <gtest/gtest.h>

namespace pdsm {
namespace {

// A 4 x 2 mask: row 0 (top) 0, 255, 0, 255; row 1 all 255.
AlphaMask Stripes(TextureWrap wrap) {
  AlphaMask mask;
  mask.width = 4;
  mask.height = 2;
  mask.alpha = {0, 255, 0, 255, 255, 255, 255, 255};
  mask.wrap_u = mask.wrap_v = wrap;
  return mask;
}

TEST(AlphaMask, TexelCentresReadTheirTexelExactlyAndBetweenIsLinear) {
  const AlphaMask mask = Stripes(TextureWrap::kClampToEdge);
  ASSERT_TRUE(mask.Valid());
  EXPECT_EQ(mask.Sample({0.125, 0.25}), 0.0);           // texel (0, 0)
  EXPECT_EQ(mask.Sample({0.375, 0.25}), 1.0);           // texel (1, 0)
  EXPECT_EQ(mask.Sample({0.125, 0.75}), 1.0);           // texel (0, 1): v grows downwards
  EXPECT_DOUBLE_EQ(mask.Sample({0.25, 0.25}), 0.5);     // halfway between (0, 0) and (1, 0)
  EXPECT_DOUBLE_EQ(mask.Sample({0.25, 0.5}), 0.75);     // the four texels' mean
  EXPECT_DOUBLE_EQ(mask.Sample({0.1875, 0.25}), 0.25);  // a quarter of the way
  EXPECT_FALSE(mask.CastsAt({0.125, 0.25}));
  EXPECT_TRUE(mask.CastsAt({0.25, 0.25}));  // 0.5 >= the 0.5 cutoff
}

TEST(AlphaMask, WrapModesChooseTheTexelBeyondTheEdge) {
  // u = -0.125 is texel -1's centre: repeat reads texel 3 (255), clamp texel 0 (0), mirror
  // texel 0 (0); u = 1.125, texel 4: repeat texel 0, clamp texel 3, mirror texel 3.
  EXPECT_EQ(Stripes(TextureWrap::kRepeat).Sample({-0.125, 0.25}), 1.0);
  EXPECT_EQ(Stripes(TextureWrap::kClampToEdge).Sample({-0.125, 0.25}), 0.0);
  EXPECT_EQ(Stripes(TextureWrap::kMirroredRepeat).Sample({-0.125, 0.25}), 0.0);
  EXPECT_EQ(Stripes(TextureWrap::kRepeat).Sample({1.125, 0.25}), 0.0);
  EXPECT_EQ(Stripes(TextureWrap::kClampToEdge).Sample({1.125, 0.25}), 1.0);
  EXPECT_EQ(Stripes(TextureWrap::kMirroredRepeat).Sample({1.125, 0.25}), 1.0);
  // Mirrored: texel 5 is texel 2 (0), texel 6 is texel 1 (255); repeat: texel 5 is texel 1.
  EXPECT_EQ(Stripes(TextureWrap::kMirroredRepeat).Sample({1.375, 0.25}), 0.0);
  EXPECT_EQ(Stripes(TextureWrap::kMirroredRepeat).Sample({1.625, 0.25}), 1.0);
  EXPECT_EQ(Stripes(TextureWrap::kRepeat).Sample({1.375, 0.25}), 1.0);
  // Far outside and negative: repeat is periodic.
  EXPECT_EQ(Stripes(TextureWrap::kRepeat).Sample({-99.875, 0.25}), 0.0);
  EXPECT_EQ(Stripes(TextureWrap::kRepeat).Sample({-99.625, 0.25}), 1.0);
}

TEST(AlphaMask, ValidChecksSizesCountsAndCutoff) {
  AlphaMask mask = Stripes(TextureWrap::kRepeat);
  EXPECT_TRUE(mask.Valid());
  mask.cutoff = 0;
  EXPECT_FALSE(mask.Valid());
  mask.cutoff = 1.5f;
  EXPECT_FALSE(mask.Valid());
  mask = Stripes(TextureWrap::kRepeat);
  mask.alpha.pop_back();
  EXPECT_FALSE(mask.Valid());
  mask = Stripes(TextureWrap::kRepeat);
  mask.width = kMaxAlphaMaskSide + 1;
  EXPECT_FALSE(mask.Valid());
  AlphaMask other = Stripes(TextureWrap::kRepeat);
  other.label = "another name";
  EXPECT_TRUE(SameMask(Stripes(TextureWrap::kRepeat), other));
  other.alpha[0] = 1;
  EXPECT_FALSE(SameMask(Stripes(TextureWrap::kRepeat), other));
}

}  // namespace
}  // namespace pdsm
