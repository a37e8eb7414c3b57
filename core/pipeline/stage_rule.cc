#include "core/pipeline/stage_rule.h"

#include <algorithm>

#include "core/bake/adaptive_sampling.h"

namespace pdsm {

StageVerdict JudgeStage(const PdsmHeader& header, TileStageState state,
                        std::vector<StageBatch> batches) {
  // Batches in sample order: the merge does not depend on it, but a fixed order costs nothing.
  std::sort(batches.begin(), batches.end(), [](const StageBatch& a, const StageBatch& b) {
    return a.sample_begin < b.sample_begin;
  });
  StageVerdict verdict;
  if (!header.adaptive()) {
    verdict.done = true;
    for (StageBatch& b : batches) verdict.events.push_back(std::move(b.events));
    return verdict;
  }
  // Merge each range of the stage, then the decision (JudgeAdaptiveStage).
  const std::vector<SampleRange> ranges =
      AdaptiveStageRanges(state.stage, std::max(1, header.adaptive_min_samples), header.samples);
  std::vector<TileEvents> range_results;
  for (const SampleRange& range : ranges) {
    std::vector<TileEvents> range_parts;
    for (StageBatch& b : batches) {
      if (b.sample_begin >= range.begin && b.sample_begin < range.end) {
        range_parts.push_back(std::move(b.events));
      }
    }
    range_results.push_back(MergeTileEvents(range_parts));
  }
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
