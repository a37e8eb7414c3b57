// The local bake under file-system faults (tests/write_faults.h): whichever write, sync or
// rename fails, and wherever the disk fills, the previous PDSM is left as it was, no
// temporary file stays, and the error names the file. (The preview's own writer has the same
// sweep in worker/preview_image_test.cc.)
#include <filesystem>

#include <gtest/gtest.h>

#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::ExamplePath;
using testing::TempDir;

Scene TinyPlates() {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(24);
  overrides.add_resolution(16);
  overrides.set_samples(4);
  overrides.set_tile_size(8);
  absl::StatusOr<Scene> scene = LoadSceneFile(ExamplePath("plates"), overrides);
  EXPECT_TRUE(scene.ok()) << scene.status();
  return *std::move(scene);
}

TEST(LocalBakeWriteFaults, PdsmIsWholeOrAsBefore) {
  TempDir dir;
  const Scene scene = TinyPlates();
  const std::string out = dir.File("out.exr");
  testing::WriteText(out, "the previous PDSM");
  testing::ExpectWriteFailuresLeaveTargetIntact(out, dir.path(), [&](FileSystem* fs) {
    LocalBakeOptions options;
    options.output_path = out;
    options.threads = 2;
    options.fs = fs;
    return RunLocalBake(scene, options).status();
  });
}

// The preview is renamed into place before the PDSM: when that fails, neither file appears.
TEST(LocalBakeWriteFaults, FailedPreviewLeavesNoPdsmEither) {
  TempDir dir;
  FaultInjectingFileSystem fs;
  fs.FailNth(FileOp::kRename, 1);
  LocalBakeOptions options;
  options.output_path = dir.File("out.exr");
  options.preview_path = dir.File("out.png");
  options.threads = 2;
  options.fs = &fs;
  const absl::Status s = RunLocalBake(TinyPlates(), options).status();
  EXPECT_FALSE(s.ok());
  EXPECT_NE(s.message().find("out.png"), std::string::npos) << s;
  EXPECT_EQ(fs.failures(), 1);
  EXPECT_TRUE(testing::FilesUnder(dir.path()).empty());
}

}  // namespace
}  // namespace pdsm
