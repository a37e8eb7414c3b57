// The bake-parameter flags shared by `pdsm bake` and `pdsm submit` (--resolution, --samples,
// --sm-resolution, --epsilon, --tile-size, --depth-bias, --sampling, --adaptive-tolerance,
// --adaptive-min-samples, --surfaces-only, --weighting, --max-refinement): they override the
// scene file's bake fields.
#ifndef PDSM_CLIENT_BAKE_OVERRIDES_H_
#define PDSM_CLIENT_BAKE_OVERRIDES_H_

#include <cstdint>
#include <optional>
#include <string>

#include <CLI/CLI.hpp>

#include "absl/status/statusor.h"
#include "pdsm/v1/scene.pb.h"

namespace pdsm {

struct OverrideFlags {
  std::string resolution;
  std::optional<int64_t> samples, sm_resolution, tile_size;
  std::optional<double> epsilon, depth_bias;
  std::string sampling;  // a bake.sampling name, any case, '-' for '_' ("blue-noise")
  std::optional<double> adaptive_tolerance;
  std::optional<int64_t> adaptive_min_samples;
  bool surfaces_only = false;             // --surfaces-only
  std::string weighting;                  // --weighting: unweighted or emitter (bake.weighting)
  std::optional<int64_t> max_refinement;  // --max-refinement: 1, 2, 4 or 8
};

void AddOverrideFlags(CLI::App* command, OverrideFlags* flags);

// The set flags as BakeParams. INVALID_ARGUMENT naming the flag for a malformed value; ranges
// are checked later with the scene's own fields (bake.samples, ...).
absl::StatusOr<pdsm::v1::BakeParams> ToBakeParams(const OverrideFlags& flags);

// A sampling pattern's name as the scene file spells bake.sampling (the proto enum's value
// names in any case, '-' for '_', so every pattern the schema knows is accepted).
// INVALID_ARGUMENT naming `flag` and listing the names otherwise.
absl::StatusOr<pdsm::v1::Sampling> ParseSamplingName(const std::string& name,
                                                     const std::string& flag);

}  // namespace pdsm

#endif  // PDSM_CLIENT_BAKE_OVERRIDES_H_
