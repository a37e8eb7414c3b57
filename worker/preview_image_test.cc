#include "worker/preview_image.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

// A 2x2 tile: one lit receiver, one in the umbra, two without a receiver.
PdsmTile Tile() {
  PdsmTile tile;
  tile.width = tile.height = 2;
  tile.vertices = {{1.0f, 0.0f}, {1.0f, 1.0f}};
  tile.offsets = {0, 0, 2, 2, 2};
  return tile;
}

// `pdsm bake` writes OUT.png through the one atomic-write path: a failure leaves the
// previous preview as it was.
TEST(PreviewImage, EveryFailureLeavesThePreviousPreview) {
  testing::TempDir dir;
  const std::string path = dir.File("out.png");
  PreviewImage blank(2, 2);
  ASSERT_TRUE(blank.Write(path).ok());
  PreviewImage shaded(2, 2);
  const float none = std::numeric_limits<float>::infinity();
  const std::vector<float> depth = {2.0f, 2.0f, none, none};
  shaded.ShadeTile(Tile(), shaded.SampledDepths(0, 0, 2, 2, depth));
  testing::ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return shaded.Write(path, fs); });
}

// A map over kMaxPreviewSide a side is shown one preview pixel per stride x stride block, by
// the block's middle pixel (the last block's clipped to the map), so its memory is bounded.
TEST(PreviewImage, AMapLargerThanThePreviewShowsOnePixelPerBlock) {
  const PreviewImage preview(2 * kMaxPreviewSide + 1, 5);
  EXPECT_EQ(preview.stride(), 3);
  EXPECT_EQ(preview.width(), (2 * kMaxPreviewSide + 1 + 2) / 3);
  EXPECT_EQ(preview.height(), 2);
  std::vector<float> depth(6 * 5);
  for (size_t i = 0; i < depth.size(); ++i) depth[i] = static_cast<float>(i);
  // Columns 1 and 4, rows 1 and 4 (the second block of rows is 3..4: its middle, 4, clipped).
  EXPECT_THAT(preview.SampledDepths(0, 0, 6, 5, depth), ::testing::ElementsAre(7, 10, 25, 28));
  // The last block of columns starts at 8190 and is 3 wide: 8191 stands for it.
  const std::vector<float> last = {0, 1, 2};
  EXPECT_THAT(preview.SampledDepths(2 * kMaxPreviewSide - 2, 1, 3, 1, last),
              ::testing::ElementsAre(1));
  // A map within the limit: every pixel.
  const PreviewImage small(kMaxPreviewSide, 5);
  EXPECT_EQ(small.stride(), 1);
  EXPECT_EQ(small.SampledDepths(0, 0, 6, 5, depth), depth);
}

}  // namespace
}  // namespace pdsm
