// A world far from its origin: examples/plates moved by (1e6, 0, -2e6). Everything goes to the
// GPU relative to the light centre (computed in double), so the GPU PDSM still matches the CPU
// query, and the image matches the one of the scene at the origin.
#include <algorithm>
#include <cmath>

#include <google/protobuf/util/json_util.h>
#include <gtest/gtest.h>

#include "client/view/image_io.h"
#include "tests/view/view_test_support.h"

namespace pdsm::testing {
namespace {

constexpr double kOffset[3] = {1e6, 0, -2e6};

std::string WriteFarPlates(const TempDir& dir) {
  absl::StatusOr<pdsm::v1::Scene> scene = ParseSceneFile(ExamplePath("plates"));
  EXPECT_TRUE(scene.ok()) << scene.status();
  for (pdsm::v1::Mesh& mesh : *scene->mutable_meshes()) {
    if (mesh.transform_size() == 0) {
      for (int i = 0; i < 16; ++i) mesh.add_transform(i % 5 == 0 ? 1 : 0);
    }
    for (int axis = 0; axis < 3; ++axis) {
      mesh.set_transform(axis * 4 + 3, mesh.transform(axis * 4 + 3) + kOffset[axis]);
    }
  }
  auto* centre = scene->mutable_light()->mutable_rect()->mutable_center();
  for (int axis = 0; axis < 3; ++axis) centre->Set(axis, centre->Get(axis) + kOffset[axis]);
  std::string json;
  EXPECT_TRUE(google::protobuf::util::MessageToJsonString(*scene, &json).ok());
  WriteText(dir.File("far.json"), json);
  return dir.File("far.json");
}

view::FloatImage Render(const std::string& scene, const std::string& pdsm, const std::string& mode,
                        const std::string& camera, const TempDir& dir) {
  const std::string pfm = dir.File(mode + std::to_string(std::hash<std::string>()(scene)) + ".pfm");
  CommandResult r =
      RunCommand(std::string(PDSM_VIEW) + " " + scene + " --pdsm " + pdsm +
                     " --headless --size 160x120 --camera " + camera + " --mode " + mode +
                     " --screenshot " + dir.File("x.png") + " --save-attenuation " + pfm,
                 dir);
  EXPECT_EQ(r.exit_code, 0) << r.err;
  absl::StatusOr<view::FloatImage> image = view::ReadPfm(pfm);
  EXPECT_TRUE(image.ok()) << image.status();
  return image.ok() ? *image : view::FloatImage{};
}

TEST(ViewFarWorld, GpuMatchesCpuAndTheSceneAtTheOrigin) {
  TempDir dir;
  const std::string far_scene = WriteFarPlates(dir);
  pdsm::v1::BakeParams overrides;  // as SmallBake
  overrides.add_resolution(64);
  overrides.add_resolution(64);
  overrides.set_samples(16);
  overrides.set_shadow_map_resolution(256);
  overrides.set_tile_size(32);
  absl::StatusOr<Scene> scene = LoadSceneFile(far_scene, overrides);
  ASSERT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions options;
  options.output_path = dir.File("far.exr");
  ASSERT_TRUE(RunLocalBake(*scene, options).ok());

  const std::string far_camera = "1000004,7,-1999994,1000000,1,-2000000,40";
  const view::FloatImage gpu = Render(far_scene, dir.File("far.exr"), "pdsm", far_camera, dir);
  const view::FloatImage cpu = Render(far_scene, dir.File("far.exr"), "cpu", far_camera, dir);
  const view::FloatImage near =
      Render(ExamplePath("plates"), SmallBake("plates"), "pdsm", "4,7,6,0,1,0,40", dir);
  ASSERT_EQ(gpu.values.size(), cpu.values.size());
  ASSERT_EQ(gpu.values.size(), near.values.size());
  size_t surface = 0, gpu_cpu_outliers = 0, far_near_outliers = 0, shadowed = 0;
  for (size_t i = 0; i < gpu.values.size(); ++i) {
    if (gpu.values[i] < 0 || cpu.values[i] < 0) {
      EXPECT_EQ(gpu.values[i], cpu.values[i]) << i;
      continue;
    }
    ++surface;
    if (cpu.values[i] > 0.5) ++shadowed;
    if (!(std::abs(gpu.values[i] - cpu.values[i]) <= 1e-4)) ++gpu_cpu_outliers;
    // The same bake up to double rounding of the offset, seen by the same camera: only
    // pixels on a shadow edge may move.
    if (!(std::abs(gpu.values[i] - near.values[i]) <= 0.02)) ++far_near_outliers;
  }
  std::printf("far world: %zu surface pixels, GPU vs CPU outliers %zu, far vs origin %zu\n",
              surface, gpu_cpu_outliers, far_near_outliers);
  EXPECT_GT(surface, gpu.values.size() / 4);
  EXPECT_GT(shadowed, surface / 50);
  EXPECT_LE(gpu_cpu_outliers, surface / 1000);
  EXPECT_LE(far_near_outliers, surface / 100);
}

}  // namespace
}  // namespace pdsm::testing
