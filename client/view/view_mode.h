// The viewer's shadow modes: the PDSM on the GPU and on the CPU, and what users would pick
// instead (shadow maps with bias, PCF, PCSS, VSM, and the average of N shadow maps).
#ifndef PDSM_CLIENT_VIEW_VIEW_MODE_H_
#define PDSM_CLIENT_VIEW_VIEW_MODE_H_

#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"

namespace pdsm::view {

// The numbers are the `mode` uniform of shaders/view/shade.frag. kShadowmask draws the
// textures `pdsm shadowmask` wrote on their receivers (--shadowmask DIR); it is not among
// kAllModes (the default --compare and keys 1-7) because it needs that folder.
enum class ViewMode {
  kPdsm = 0,
  kCpu = 1,
  kHard = 2,
  kPcf = 3,
  kPcss = 4,
  kVsm = 5,
  kMultiSm = 6,
  kShadowmask = 7,
};

inline constexpr ViewMode kAllModes[] = {ViewMode::kPdsm,   ViewMode::kCpu,  ViewMode::kHard,
                                         ViewMode::kPcf,    ViewMode::kPcss, ViewMode::kVsm,
                                         ViewMode::kMultiSm};

// "pdsm", "cpu", "hard", "pcf", "pcss", "vsm", "multi-sm", "shadowmask".
const char* ModeName(ViewMode mode);
std::optional<ViewMode> ModeFromName(const std::string& name);

// A comma-separated list ("pdsm,cpu,hard"); INVALID_ARGUMENT naming `flag` and the bad entry.
absl::StatusOr<std::vector<ViewMode>> ParseModeList(const std::string& list,
                                                    const std::string& flag);

// Modes that need shadow maps rendered from the light.
inline bool UsesShadowMap(ViewMode mode) {
  return mode == ViewMode::kHard || mode == ViewMode::kPcf || mode == ViewMode::kPcss ||
         mode == ViewMode::kVsm;
}

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_VIEW_MODE_H_
