#include "client/measure/bake_knobs.h"

#include <regex>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/scene/scene_loader.h"

namespace pdsm {

std::vector<std::string> BakeKnobs::BakeArgs() const {
  std::vector<std::string> args = {"--samples",       absl::StrCat(samples),
                                   "--resolution",    absl::StrCat(width, "x", height),
                                   "--sm-resolution", absl::StrCat(sm_resolution),
                                   "--epsilon",       absl::StrFormat("%.17g", epsilon),
                                   "--sampling",      sampling};
  if (depth_bias) {
    args.push_back("--depth-bias");
    args.push_back(absl::StrFormat("%.17g", *depth_bias));
  }
  return args;
}

std::string BakeKnobs::Label() const {
  std::string label = absl::StrFormat("s%d_r%dx%d_sm%d_e%g_%s", samples, width, height,
                                      sm_resolution, epsilon, sampling);
  if (depth_bias) absl::StrAppendFormat(&label, "_b%g", *depth_bias);
  return label;
}

BakeKnobs KnobsFromScene(const Scene& scene, const std::string& sampling_name) {
  BakeKnobs knobs;
  knobs.samples = scene.bake.samples;
  knobs.width = scene.bake.width;
  knobs.height = scene.bake.height;
  knobs.sm_resolution = scene.bake.shadow_map_resolution;
  knobs.epsilon = scene.bake.epsilon;
  knobs.sampling = sampling_name;
  knobs.depth_bias = scene.bake.depth_bias;
  return knobs;
}

absl::StatusOr<std::string> SceneSamplingName(const std::string& scene_path) {
  absl::StatusOr<pdsm::v1::Scene> message = ParseSceneFile(scene_path);
  if (!message.ok()) return message.status();
  // The loader's effective value: an unset pattern is the default it applies (SOBOL).
  absl::StatusOr<pdsm::v1::BakeParams> effective = EffectiveBakeParams(*message, scene_path);
  if (!effective.ok()) return effective.status();
  return pdsm::v1::Sampling_Name(effective->sampling());
}

absl::StatusOr<std::pair<int, int>> ParseResolution(const std::string& text,
                                                    const std::string& flag) {
  static const std::regex kWxH(R"((\d{1,5})(?:x(\d{1,5}))?)");
  std::smatch m;
  if (!std::regex_match(text, m, kWxH)) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: expected WIDTHxHEIGHT or a size, e.g. 512x512 or 512 (got \"%s\")", flag, text));
  }
  const int w = std::stoi(m[1]);
  const int h = m[2].matched ? std::stoi(m[2]) : w;
  return std::make_pair(w, h);
}

}  // namespace pdsm
