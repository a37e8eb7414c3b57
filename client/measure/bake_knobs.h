// The knobs a sweep varies and `--target-error` chooses, as one bake configuration: turned into
// `pdsm bake` flags for a child process and into CSV cells.
#ifndef PDSM_CLIENT_MEASURE_BAKE_KNOBS_H_
#define PDSM_CLIENT_MEASURE_BAKE_KNOBS_H_

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/scene/scene.h"

namespace pdsm {

struct BakeKnobs {
  int samples = 0;
  int width = 0, height = 0;  // PDSM resolution
  int sm_resolution = 0;
  double epsilon = 0;
  std::string sampling;              // a bake.sampling name
  std::optional<double> depth_bias;  // unset: the plan's default

  // The `pdsm bake` flags that set every knob.
  std::vector<std::string> BakeArgs() const;
  // "s64_r256x256_sm512_e0.01_STRATIFIED[_b0.001]": a file-name-safe label.
  std::string Label() const;
};

// The scene's own values (the file's bake fields with their defaults).
BakeKnobs KnobsFromScene(const Scene& scene, const std::string& sampling_name);

// bake.sampling of the scene file as its name (e.g. "STRATIFIED"); errors of ParseSceneFile.
absl::StatusOr<std::string> SceneSamplingName(const std::string& scene_path);

// "512x256" or "512" (square).
absl::StatusOr<std::pair<int, int>> ParseResolution(const std::string& text,
                                                    const std::string& flag);

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_BAKE_KNOBS_H_
