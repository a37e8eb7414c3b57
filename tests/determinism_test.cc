// Same input, same bytes: the file must not depend on threads or on how samples are batched
// into tasks (the distributed service relies on this).
#include <gtest/gtest.h>

#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm {
namespace {

using testing::ExamplePath;
using testing::ReadBytes;
using testing::TempDir;

std::string Bake(const std::string& example, int threads, int samples_per_task, const TempDir& dir,
                 const std::string& name) {
  pdsm::v1::BakeParams overrides;
  overrides.add_resolution(72);
  overrides.add_resolution(40);
  overrides.set_samples(13);
  overrides.set_tile_size(16);
  auto scene = LoadSceneFile(ExamplePath(example), overrides);
  EXPECT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions options;
  options.output_path = dir.File(name);
  options.threads = threads;
  options.samples_per_task = samples_per_task;
  auto summary = RunLocalBake(*scene, options);
  EXPECT_TRUE(summary.ok()) << summary.status();
  EXPECT_GT(summary->assembly.vertices, 0);
  return ReadBytes(options.output_path);
}

TEST(Determinism, SameBytesForAnyThreadsAndBatches) {
  TempDir dir;
  const std::string reference = Bake("plates", 1, 0, dir, "a.exr");
  ASSERT_FALSE(reference.empty());
  EXPECT_EQ(Bake("plates", 2, 0, dir, "b.exr"), reference);
  EXPECT_EQ(Bake("plates", 2, 5, dir, "c.exr"), reference);
  EXPECT_EQ(Bake("plates", 3, 1, dir, "d.exr"), reference);
}

TEST(Determinism, SunSameBytesForAnyThreadsAndBatches) {
  TempDir dir;
  const std::string reference = Bake("sun_pillars", 1, 0, dir, "a.exr");
  ASSERT_FALSE(reference.empty());
  EXPECT_EQ(Bake("sun_pillars", 2, 4, dir, "b.exr"), reference);
}

}  // namespace
}  // namespace pdsm
