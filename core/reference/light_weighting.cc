#include "core/reference/light_weighting.h"

#include "absl/strings/str_format.h"

namespace pdsm {

absl::StatusOr<LightWeighting> ParseLightWeighting(const std::string& text,
                                                   const std::string& flag) {
  for (LightWeighting w :
       {LightWeighting::kUnweighted, LightWeighting::kEmitter, LightWeighting::kIrradiance}) {
    if (text == LightWeightingName(w)) return w;
  }
  return absl::InvalidArgumentError(
      absl::StrFormat("%s: expected unweighted, emitter or irradiance (got \"%s\")", flag, text));
}

const char* LightWeightingName(LightWeighting weighting) {
  switch (weighting) {
    case LightWeighting::kUnweighted:
      return "unweighted";
    case LightWeighting::kEmitter:
      return "emitter";
    case LightWeighting::kIrradiance:
      return "irradiance";
  }
  return "?";
}

}  // namespace pdsm
