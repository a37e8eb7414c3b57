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
  shaded.ShadeTile(Tile(), depth);
  testing::ExpectWriteFailuresLeaveTargetIntact(
      path, dir.path(), [&](FileSystem* fs) { return shaded.Write(path, fs); });
}

}  // namespace
}  // namespace pdsm
