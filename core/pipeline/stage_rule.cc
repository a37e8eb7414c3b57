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
    : ranges_(StageRanges(header, stage)), merged_(ranges_.size()), keying_(KeyingOf(header)) {}

int64_t StageAccumulator::Add(int sample_begin, TileEvents events) {
  for (size_t r = 0; r < ranges_.size(); ++r) {
    if (sample_begin < ranges_[r].begin || sample_begin >= ranges_[r].end) continue;
    if (shape_.PixelCount() == 0) shape_ = TileShape(events);
    std::optional<TileEvents>& merged = merged_[r].merged;
    if (merged && events.events.empty()) return 0;  // a batch that shadows nothing adds nothing
    const int64_t before = merged ? TileEventsBytes(*merged) : 0;
    if (!merged) {
      merged = std::move(events);
    } else {
      const TileEvents parts[2] = {*std::move(merged), std::move(events)};
      merged = MergeTileEvents(parts, keying_);
    }
    const int64_t change = TileEventsBytes(*merged) - before;
    memory_bytes_ += change;
    return change;
  }
  return 0;
}

absl::Status StageAccumulator::Spill(EventSpill* spill) {
  std::vector<std::optional<SpilledRun>> written(merged_.size());
  for (size_t r = 0; r < merged_.size(); ++r) {
    const std::optional<TileEvents>& merged = merged_[r].merged;
    if (!merged || merged->events.empty()) continue;  // nothing a run would add
    absl::StatusOr<SpilledRun> run = spill->Write(*merged);
    if (!run.ok()) return run.status();
    written[r] = *run;
  }
  for (size_t r = 0; r < merged_.size(); ++r) {
    if (!written[r]) continue;
    merged_[r].runs.push_back(*written[r]);
    memory_bytes_ -= TileEventsBytes(*merged_[r].merged);
    merged_[r].merged.reset();
  }
  return absl::OkStatus();
}

std::vector<TileParts> StageAccumulator::TakeRanges() {
  std::vector<TileParts> out(merged_.size());
  for (size_t r = 0; r < merged_.size(); ++r) {
    Range& range = merged_[r];
    out[r].shape = shape_;
    if (range.merged) out[r].in_memory.push_back(*std::move(range.merged));
    out[r].spilled = std::move(range.runs);
  }
  merged_.assign(ranges_.size(), Range{});
  memory_bytes_ = 0;
  return out;
}

absl::StatusOr<StageVerdict> JudgeStage(const PdsmHeader& header, TileStageState state,
                                        std::vector<TileParts> ranges, EventSpill* spill) {
  StageVerdict verdict;
  if (!header.adaptive()) {
    verdict.done = true;
    verdict.events = std::move(ranges.at(0));
    return verdict;
  }
  // The adaptive rule compares ranges' merged lists, in memory.
  std::vector<TileEvents> range_results;
  range_results.reserve(ranges.size());
  for (TileParts& parts : ranges) {
    for (const SpilledRun& run : parts.spilled) {
      absl::StatusOr<TileEvents> read = spill->ReadAndRelease(run, parts.shape);
      if (!read.ok()) return read.status();
      parts.in_memory.push_back(*std::move(read));
    }
    if (parts.in_memory.empty()) {
      range_results.push_back(parts.shape);
      range_results.back().offsets.assign(parts.shape.PixelCount() + 1, 0);
    } else if (parts.in_memory.size() == 1) {
      range_results.push_back(std::move(parts.in_memory.front()));
    } else {
      range_results.push_back(MergeTileEvents(parts.in_memory, KeyingOf(header)));
    }
  }
  const std::vector<SampleRange> stage_ranges = StageRanges(header, state.stage);
  const int samples = stage_ranges.back().end;
  if (JudgeAdaptiveStage(header, stage_ranges, std::move(range_results), &state.earlier)) {
    verdict.done = true;
    verdict.events.shape = ranges.at(0).shape;
    verdict.events.in_memory = std::move(state.earlier);
    verdict.tile_samples = samples;
    verdict.samples_skipped = header.samples - samples;
    return verdict;
  }
  verdict.next.stage = state.stage + 1;
  verdict.next.earlier = std::move(state.earlier);
  return verdict;
}

}  // namespace pdsm
