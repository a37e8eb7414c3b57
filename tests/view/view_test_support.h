// Shared by the pdsm-view tests: small bakes of the examples (made once per test process) and
// running the pdsm-view binary.
#ifndef PDSM_TESTS_VIEW_VIEW_TEST_SUPPORT_H_
#define PDSM_TESTS_VIEW_VIEW_TEST_SUPPORT_H_

#include <map>
#include <string>

#include "core/scene/scene_loader.h"
#include "tests/test_support.h"
#include "worker/local_bake.h"

namespace pdsm::testing {

// The folder of the bakes; lives as long as the test process.
inline const TempDir& ViewBakeDir() {
  static const TempDir* dir = new TempDir();
  return *dir;
}

// `example` baked at resolution^2 PDSM pixels in 32-pixel tiles into the bakes' folder as
// `file_name`; returns its path. Same bytes every time (determinism).
inline std::string BakeExample(const std::string& example, const std::string& file_name,
                               int resolution, int samples, int shadow_map_resolution,
                               bool surfaces_only = false) {
  pdsm::v1::BakeParams overrides;
  overrides.set_surfaces_only(surfaces_only);
  overrides.add_resolution(resolution);
  overrides.add_resolution(resolution);
  overrides.set_samples(samples);
  overrides.set_shadow_map_resolution(shadow_map_resolution);
  overrides.set_tile_size(32);
  absl::StatusOr<Scene> scene = LoadSceneFile(ExamplePath(example), overrides);
  EXPECT_TRUE(scene.ok()) << scene.status();
  LocalBakeOptions options;
  options.output_path = ViewBakeDir().File(file_name);
  absl::StatusOr<BakeSummary> summary = RunLocalBake(*scene, options);
  EXPECT_TRUE(summary.ok()) << summary.status();
  return options.output_path;
}

// `example` baked at 64x64 PDSM pixels, 16 samples, 256-texel shadow maps: a few tenths of a
// second, and enough penumbra to compare modes on. Same bytes every time (determinism).
// `surfaces_only`: the same bake keeping A(z) only near the receivers (NaN elsewhere).
inline std::string SmallBake(const std::string& example, bool surfaces_only = false) {
  static std::map<std::string, std::string>* baked = new std::map<std::string, std::string>();
  const std::string name = example + (surfaces_only ? "_surfaces_only" : "");
  if (auto it = baked->find(name); it != baked->end()) return it->second;
  (*baked)[name] = BakeExample(example, name + ".exr", 64, 16, 256, surfaces_only);
  return (*baked)[name];
}

// pdsm-view with `args` appended after the scene of `example`.
inline CommandResult RunView(const std::string& example, const std::string& args,
                             const TempDir& dir) {
  return RunCommand(std::string(PDSM_VIEW) + " " + ExamplePath(example) + " " + args, dir);
}

// Where failing image tests leave their actual and diff images (kept after the test).
inline std::string ViewTestOutputDir() {
  const std::string dir = std::string(PDSM_BINARY_DIR) + "/test-output/view";
  std::filesystem::create_directories(dir);
  return dir;
}

}  // namespace pdsm::testing

#endif  // PDSM_TESTS_VIEW_VIEW_TEST_SUPPORT_H_
