#include "core/pipeline/stage_rule.h"

#include <algorithm>
#include <utility>

namespace pdsm {

std::vector<SampleRange> StageRanges(const PdsmHeader& header, int stage) {
  if (!header.adaptive()) {
    if (stage > 0) return {};
    return {SampleRange{0, header.samples}};
  }
  return AdaptiveStageRanges(stage, std::max(1, header.adaptive_min_samples), header.samples);
}

StageAccumulator::StageAccumulator(const PdsmHeader& header, int stage)
    : ranges_(StageRanges(header, stage)), merged_(ranges_.size()) {}

void StageAccumulator::Add(int sample_begin, TileEvents events) {
  for (size_t r = 0; r < ranges_.size(); ++r) {
    if (sample_begin < ranges_[r].begin || sample_begin >= ranges_[r].end) continue;
    if (!merged_[r]) {
      merged_[r] = std::move(events);
    } else {
      const TileEvents parts[2] = {*std::move(merged_[r]), std::move(events)};
      merged_[r] = MergeTileEvents(parts);
    }
    return;
  }
}

std::vector<TileEvents> StageAccumulator::TakeRanges() {
  std::vector<TileEvents> out;
  out.reserve(merged_.size());
  for (std::optional<TileEvents>& m : merged_) out.push_back(m ? *std::move(m) : TileEvents{});
  merged_.assign(ranges_.size(), std::nullopt);
  return out;
}

StageVerdict JudgeStage(const PdsmHeader& header, TileStageState state,
                        std::vector<TileEvents> range_results) {
  StageVerdict verdict;
  if (!header.adaptive()) {
    verdict.done = true;
    verdict.events = std::move(range_results);
    return verdict;
  }
  const std::vector<SampleRange> ranges = StageRanges(header, state.stage);
  const int samples = ranges.back().end;
  if (JudgeAdaptiveStage(header, ranges, std::move(range_results), &state.earlier)) {
    verdict.done = true;
    verdict.events = std::move(state.earlier);
    verdict.tile_samples = samples;
    verdict.samples_skipped = header.samples - samples;
    return verdict;
  }
  verdict.next.stage = state.stage + 1;
  verdict.next.earlier = std::move(state.earlier);
  return verdict;
}

}  // namespace pdsm
