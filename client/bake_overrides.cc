#include "client/bake_overrides.h"

#include <algorithm>
#include <regex>
#include <vector>

#include "absl/strings/ascii.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"

namespace pdsm {

void AddOverrideFlags(CLI::App* cmd, OverrideFlags* flags) {
  cmd->add_option("--resolution", flags->resolution, "PDSM resolution WIDTHxHEIGHT");
  cmd->add_option("--samples", flags->samples, "Light samples");
  cmd->add_option("--sm-resolution", flags->sm_resolution, "Shadow-map texels across the window");
  cmd->add_option("--epsilon", flags->epsilon, "Compression tolerance in [0, 1]");
  cmd->add_option("--tile-size", flags->tile_size, "PDSM pixels per tile side");
  cmd->add_option("--sampling", flags->sampling,
                  "Light sample pattern: stratified, uniform, sobol, halton, blue-noise");
  cmd->add_option("--adaptive-tolerance", flags->adaptive_tolerance,
                  "Adaptive sampling: stop adding samples to a tile once its estimated error is "
                  "at most this; --samples becomes the per-tile maximum (0: off)");
  cmd->add_option("--adaptive-min-samples", flags->adaptive_min_samples,
                  "Adaptive sampling: samples of a tile's first batch");
  cmd->add_flag("--surfaces-only", flags->surfaces_only,
                "Keep A(z) only near receiver surfaces (static receivers; elsewhere NaN)");
  cmd->add_option("--depth-bias", flags->depth_bias, "Constant depth bias, world units");
  cmd->add_option("--weighting", flags->weighting,
                  "What a light sample counts for: unweighted (the fraction of the light's area "
                  "hidden) or emitter (its power toward the point, cos/r^2: the fraction of the "
                  "light's solid angle hidden)");
  cmd->add_option("--max-refinement", flags->max_refinement,
                  "Adaptive resolution: refine pixels whose penumbra is narrower than a pixel, "
                  "up to 1 (off), 2, 4 or 8 times per axis");
}

absl::StatusOr<pdsm::v1::Sampling> ParseSamplingName(const std::string& name,
                                                     const std::string& flag) {
  // Any case, '-' for '_': "blue-noise", "SOBOL" and "Halton" all name a bake.sampling value.
  std::string upper = absl::AsciiStrToUpper(name);
  std::replace(upper.begin(), upper.end(), '-', '_');
  pdsm::v1::Sampling value;
  if (upper != "SAMPLING_DEFAULT" && pdsm::v1::Sampling_Parse(upper, &value)) return value;
  std::vector<std::string> names;
  const google::protobuf::EnumDescriptor* e = pdsm::v1::Sampling_descriptor();
  for (int i = 0; i < e->value_count(); ++i) {  // as users type them: "blue-noise"
    if (e->value(i)->number() == 0) continue;
    std::string spelled = absl::AsciiStrToLower(e->value(i)->name());
    std::replace(spelled.begin(), spelled.end(), '_', '-');
    names.push_back(spelled);
  }
  return absl::InvalidArgumentError(absl::StrFormat(
      "%s: unknown sampling pattern \"%s\" (one of %s)", flag, name, absl::StrJoin(names, ", ")));
}

absl::StatusOr<pdsm::v1::BakeParams> ToBakeParams(const OverrideFlags& flags) {
  pdsm::v1::BakeParams params;
  if (!flags.resolution.empty()) {
    std::smatch m;
    static const std::regex kWxH(R"((\d{1,9})x(\d{1,9}))");
    if (!std::regex_match(flags.resolution, m, kWxH)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "--resolution: expected WIDTHxHEIGHT, e.g. 512x512 (got \"%s\")", flags.resolution));
    }
    params.add_resolution(std::stoul(m[1]));
    params.add_resolution(std::stoul(m[2]));
  }
  // Values are range-checked with the scene's own fields (bake.samples, ...).
  auto set_count = [](const char* flag, const std::optional<int64_t>& value,
                      auto setter) -> absl::Status {
    if (!value) return absl::OkStatus();
    if (*value < 0 || *value > UINT32_MAX) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: must be a positive count (got %d)", flag, *value));
    }
    setter(static_cast<uint32_t>(*value));
    return absl::OkStatus();
  };
  absl::Status s =
      set_count("--samples", flags.samples, [&](uint32_t v) { params.set_samples(v); });
  if (s.ok()) {
    s = set_count("--sm-resolution", flags.sm_resolution,
                  [&](uint32_t v) { params.set_shadow_map_resolution(v); });
  }
  if (s.ok()) {
    s = set_count("--tile-size", flags.tile_size, [&](uint32_t v) { params.set_tile_size(v); });
  }
  if (s.ok()) {
    s = set_count("--adaptive-min-samples", flags.adaptive_min_samples,
                  [&](uint32_t v) { params.set_adaptive_min_samples(v); });
  }
  if (s.ok()) {
    s = set_count("--max-refinement", flags.max_refinement,
                  [&](uint32_t v) { params.set_max_refinement(v); });
  }
  if (!s.ok()) return s;
  if (flags.epsilon) params.set_epsilon(*flags.epsilon);
  if (flags.adaptive_tolerance) params.set_adaptive_tolerance(*flags.adaptive_tolerance);
  if (flags.surfaces_only) params.set_surfaces_only(true);
  if (flags.depth_bias) params.set_depth_bias(*flags.depth_bias);
  if (flags.weighting == "unweighted") {
    params.set_weighting(pdsm::v1::UNWEIGHTED);
  } else if (flags.weighting == "emitter") {
    params.set_weighting(pdsm::v1::EMITTER);
  } else if (!flags.weighting.empty()) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "--weighting: unknown weighting \"%s\" (one of unweighted, emitter)", flags.weighting));
  }
  if (!flags.sampling.empty()) {
    absl::StatusOr<pdsm::v1::Sampling> sampling = ParseSamplingName(flags.sampling, "--sampling");
    if (!sampling.ok()) return sampling.status();
    params.set_sampling(*sampling);
  }
  return params;
}

}  // namespace pdsm
