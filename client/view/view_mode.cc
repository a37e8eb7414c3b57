#include "client/view/view_mode.h"

#include "absl/strings/str_cat.h"
#include "absl/strings/str_split.h"

namespace pdsm::view {

const char* ModeName(ViewMode mode) {
  switch (mode) {
    case ViewMode::kPdsm:
      return "pdsm";
    case ViewMode::kCpu:
      return "cpu";
    case ViewMode::kHard:
      return "hard";
    case ViewMode::kPcf:
      return "pcf";
    case ViewMode::kPcss:
      return "pcss";
    case ViewMode::kVsm:
      return "vsm";
    case ViewMode::kMultiSm:
      return "multi-sm";
    case ViewMode::kShadowmask:
      return "shadowmask";
  }
  return "?";
}

std::optional<ViewMode> ModeFromName(const std::string& name) {
  for (ViewMode mode : kAllModes) {
    if (name == ModeName(mode)) return mode;
  }
  if (name == ModeName(ViewMode::kShadowmask)) return ViewMode::kShadowmask;
  return std::nullopt;
}

absl::StatusOr<std::vector<ViewMode>> ParseModeList(const std::string& list,
                                                    const std::string& flag) {
  std::vector<ViewMode> modes;
  for (absl::string_view part : absl::StrSplit(list, ',')) {
    std::optional<ViewMode> mode = ModeFromName(std::string(part));
    if (!mode) {
      return absl::InvalidArgumentError(
          absl::StrCat(flag, ": unknown mode \"", part,
                       "\" (pdsm, cpu, hard, pcf, pcss, vsm, multi-sm, shadowmask)"));
    }
    modes.push_back(*mode);
  }
  return modes;
}

}  // namespace pdsm::view
