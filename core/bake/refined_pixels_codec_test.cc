#include "core/bake/refined_pixels_codec.h"

#include <gtest/gtest.h>

#include <cstring>
#include <limits>
#include <string>
#include <vector>

#include "core/util/little_endian.h"

namespace pdsm {
namespace {

// A 40 x 24 base map in tiles of 16: a 3 x 2 grid whose edge tiles are cut.
BakePlan GridPlan() {
  BakePlan plan;
  plan.header.geometry.width = 40;
  plan.header.geometry.height = 24;
  plan.header.tile_size = 16;
  plan.tiles_x = 3;
  plan.tiles_y = 2;
  return plan;
}

RefinedPixels Sample(const BakePlan& plan) {
  std::vector<std::vector<RefinedPixel>> by_tile(plan.tile_count());
  by_tile[0] = {{3, 4, {{1.0, 1.5}}}, {15, 4, {{0.25, 0.5}, {2.0, 2.0 + 1e-12}}}};
  by_tile[5] = {{39, 23, {{-3.0, 7.125}}}};  // the cut corner tile
  return RefinedPixels(plan.header.geometry, plan.header.tile_size, 4, std::move(by_tile));
}

TEST(RefinedPixelsCodec, RoundTripsBitForBit) {
  const BakePlan plan = GridPlan();
  const RefinedPixels refined = Sample(plan);
  const std::string bytes = EncodeRefinedPixels(refined);
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> back =
      DecodeRefinedPixels(bytes, plan, "blob");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_EQ((*back)->factor(), 4);
  EXPECT_EQ((*back)->count(), 3);
  ASSERT_EQ((*back)->tiles(), plan.tile_count());
  for (int t = 0; t < plan.tile_count(); ++t) {
    ASSERT_EQ((*back)->Tile(t).size(), refined.Tile(t).size()) << t;
    for (size_t k = 0; k < refined.Tile(t).size(); ++k) {
      EXPECT_EQ((*back)->Tile(t)[k], refined.Tile(t)[k]) << t << " " << k;
    }
  }
  EXPECT_EQ(EncodeRefinedPixels(**back), bytes);
}

TEST(RefinedPixelsCodec, NothingRefinedIsAValidBlob) {
  const BakePlan plan = GridPlan();
  const RefinedPixels none(plan.header.geometry, plan.header.tile_size, 2,
                           std::vector<std::vector<RefinedPixel>>(plan.tile_count()));
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> back =
      DecodeRefinedPixels(EncodeRefinedPixels(none), plan, "blob");
  ASSERT_TRUE(back.ok()) << back.status();
  EXPECT_TRUE((*back)->empty());
}

// Every damage is DATA_LOSS naming the blob, never a crash or a huge allocation.
void ExpectRefused(const std::string& bytes, const BakePlan& plan, const std::string& what) {
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> back =
      DecodeRefinedPixels(bytes, plan, "job j light 0");
  ASSERT_FALSE(back.ok()) << what;
  EXPECT_TRUE(absl::IsDataLoss(back.status())) << what << ": " << back.status();
  EXPECT_NE(back.status().message().find("job j light 0"), std::string::npos) << back.status();
}

TEST(RefinedPixelsCodec, DamageIsDataLossNamingTheBlob) {
  const BakePlan plan = GridPlan();
  const std::string good = EncodeRefinedPixels(Sample(plan));
  // Offsets into the layout of Sample(): header 20 bytes, tile 0's count at 20, its first
  // pixel's x at 24, y at 28, band count at 32, first band at 36.
  const auto with_u32 = [&](size_t at, uint32_t v) {
    std::string b = good;
    ByteWriter(b.data() + at).U32(v);
    return b;
  };
  const auto with_f64 = [&](size_t at, double v) {
    std::string b = good;
    ByteWriter(b.data() + at).F64(v);
    return b;
  };
  ExpectRefused("", plan, "empty");
  ExpectRefused("PDSMMESH" + good.substr(8), plan, "magic");
  ExpectRefused(with_u32(8, 2), plan, "version");
  ExpectRefused(with_u32(12, 3), plan, "factor 3");
  ExpectRefused(with_u32(16, 5), plan, "tile count");
  ExpectRefused(with_u32(20, 0xffffffffu), plan, "pixel count past the bytes");
  ExpectRefused(with_u32(24, 16), plan, "pixel outside its tile");
  ExpectRefused(with_u32(24, 15), plan, "pixels out of order");  // (15,4) twice
  ExpectRefused(with_u32(32, 0), plan, "no band");
  ExpectRefused(with_u32(32, 1u << 30), plan, "band count past the bytes");
  ExpectRefused(with_f64(36, std::numeric_limits<double>::quiet_NaN()), plan, "NaN band");
  ExpectRefused(with_f64(36, 2.0), plan, "empty band");
  ExpectRefused(good.substr(0, good.size() - 1), plan, "cut short");
  ExpectRefused(good + "x", plan, "left over");
  BakePlan other = plan;
  other.tiles_x = 2;
  ExpectRefused(good, other, "another grid");
}

}  // namespace
}  // namespace pdsm
