// What a tile's completed stage of work becomes: the one rule every bake shares (the local
// bake and the coordinator both call it through core/pipeline/bake_engine.h), so their files
// are the same bytes by construction.
//
// A fixed-count bake has one stage per tile holding every sample: its merged batches are the
// tile. An adaptive bake (core/bake/adaptive_sampling.h, docs/algorithms.md section 9) has
// stages of doubling sample ranges: after each, JudgeAdaptiveStage decides from the merged
// integer counts whether the tile is done or needs its next stage. Neither depends on how the
// stage's samples were cut into batches, nor on the order the batches arrived.
#ifndef PDSM_CORE_PIPELINE_STAGE_RULE_H_
#define PDSM_CORE_PIPELINE_STAGE_RULE_H_

#include <optional>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/bake/adaptive_sampling.h"
#include "core/events/event.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pipeline/event_spill.h"

namespace pdsm {

// The sample ranges of stage `stage` of a tile: [0, samples) for a fixed-count bake (stage 0),
// AdaptiveStageRanges for an adaptive one.
std::vector<SampleRange> StageRanges(const PdsmHeader& header, int stage);

// One tile's batches of its current stage, merged as they arrive: one merged list per range of
// the stage, whatever the number of batches. The merge is exact integer addition (or, for
// sample-keyed events, an interleaving by depth and key), so the lists do not depend on the
// batches or their order. The lists grow with the samples (nearly every
// event of a penumbra has a depth of its own): the engine moves them to an EventSpill as runs
// when its memory budget is spent, and TakeRanges merges the runs back, to the same lists.
// Not thread-safe.
class StageAccumulator {
 public:
  StageAccumulator(const PdsmHeader& header, int stage);

  // Merges a batch in. Returns the change in MemoryBytes().
  // REQUIRES: `sample_begin` lies in a range of the stage; `events` are of this tile.
  int64_t Add(int sample_begin, TileEvents events);

  // The bytes its lists hold in memory (TileEventsBytes).
  int64_t MemoryBytes() const { return memory_bytes_; }

  // Moves the lists held in memory to `spill` as one run per range; MemoryBytes() becomes 0.
  // On error nothing moved.
  absl::Status Spill(EventSpill* spill);

  // The events of each range, in range order: its lists in memory and its runs in the
  // spill, unmerged (the assembly merges them pixel by pixel, reading the runs a piece at a
  // time, so a tile's merged lists are never all in memory). REQUIRES: every range got a batch.
  std::vector<TileParts> TakeRanges();

 private:
  struct Range {
    std::optional<TileEvents> merged;  // in memory
    std::vector<SpilledRun> runs;      // in the spill
  };
  std::vector<SampleRange> ranges_;
  std::vector<Range> merged_;
  TileEvents shape_;  // the tile's index and rectangle, without lists
  EventKeying keying_;
  int64_t memory_bytes_ = 0;
};

// An open tile between stages.
struct TileStageState {
  int stage = 0;                    // the stage whose batches are being collected
  std::vector<TileEvents> earlier;  // adaptive bakes: merged events of the earlier stages
};

struct StageVerdict {
  bool done = false;
  // done: the events to assemble, in parts (they cover the tile's samples exactly once) and the
  // tile's sample count for AssemblePlanTile: 0 for a fixed-count bake (the header's count).
  TileParts events;
  int tile_samples = 0;
  // Samples a converged adaptive tile will never take (header.samples - its samples); 0
  // otherwise. Progress counts them as done, so a finished job reads 1.
  int samples_skipped = 0;
  // !done: the tile's state for its next stage (stage + 1).
  TileStageState next;
};

// REQUIRES: `ranges` are the events of every range of stage `state.stage`
// (StageAccumulator::TakeRanges) of one tile; `spill` holds their runs (null when they have
// none). A fixed-count stage is the tile, its parts as they are; an adaptive one reads its
// runs back to judge the stage. Errors: the spill's.
absl::StatusOr<StageVerdict> JudgeStage(const PdsmHeader& header, TileStageState state,
                                        std::vector<TileParts> ranges, EventSpill* spill);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_STAGE_RULE_H_
