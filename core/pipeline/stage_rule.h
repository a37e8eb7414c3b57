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

#include "core/bake/adaptive_sampling.h"
#include "core/events/event.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// The sample ranges of stage `stage` of a tile: [0, samples) for a fixed-count bake (stage 0),
// AdaptiveStageRanges for an adaptive one.
std::vector<SampleRange> StageRanges(const PdsmHeader& header, int stage);

// One tile's batches of its current stage, merged as they arrive: one merged list per range of
// the stage, whatever the number of batches, so memory does not grow with the samples. The
// merge is exact integer addition, so the lists do not depend on the batches or their order.
// Not thread-safe.
class StageAccumulator {
 public:
  StageAccumulator(const PdsmHeader& header, int stage);

  // REQUIRES: `sample_begin` lies in a range of the stage; `events` are of this tile.
  void Add(int sample_begin, TileEvents events);

  // The merged events of each range, in range order. REQUIRES: every range got a batch.
  std::vector<TileEvents> TakeRanges();

 private:
  std::vector<SampleRange> ranges_;
  std::vector<std::optional<TileEvents>> merged_;
};

// An open tile between stages.
struct TileStageState {
  int stage = 0;                    // the stage whose batches are being collected
  std::vector<TileEvents> earlier;  // adaptive bakes: merged events of the earlier stages
};

struct StageVerdict {
  bool done = false;
  // done: the events to assemble (they cover the tile's samples exactly once) and the tile's
  // sample count for AssemblePlanTile: 0 for a fixed-count bake (the header's count).
  std::vector<TileEvents> events;
  int tile_samples = 0;
  // Samples a converged adaptive tile will never take (header.samples - its samples); 0
  // otherwise. Progress counts them as done, so a finished job reads 1.
  int samples_skipped = 0;
  // !done: the tile's state for its next stage (stage + 1).
  TileStageState next;
};

// REQUIRES: `range_results` are the merged events of every range of stage `state.stage`
// (StageAccumulator::TakeRanges) of one tile.
StageVerdict JudgeStage(const PdsmHeader& header, TileStageState state,
                        std::vector<TileEvents> range_results);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_STAGE_RULE_H_
