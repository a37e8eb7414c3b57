// What a tile's completed stage of work becomes: the one rule every bake shares (the local
// bake and the coordinator both call it through core/pipeline/bake_engine.h), so their files
// are the same bytes by construction.
//
// A fixed-count bake has one stage per tile holding every sample: its batches are the tile.
// An adaptive bake (core/bake/adaptive_sampling.h, docs/algorithms.md section 9) has stages of
// doubling sample ranges: after each, JudgeAdaptiveStage decides from the merged integer counts
// whether the tile is done or needs its next stage. Neither depends on how the stage's samples
// were cut into batches, nor on the order the batches arrived.
#ifndef PDSM_CORE_PIPELINE_STAGE_RULE_H_
#define PDSM_CORE_PIPELINE_STAGE_RULE_H_

#include <vector>

#include "core/events/event.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm {

// One accepted batch of a tile: the events of samples [sample_begin, ...).
struct StageBatch {
  int sample_begin = 0;
  TileEvents events;
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

// REQUIRES: `batches` are every batch of stage `state.stage` of one tile, each once, in any
// order; for a fixed-count header that stage is 0 and the batches cover every sample.
StageVerdict JudgeStage(const PdsmHeader& header, TileStageState state,
                        std::vector<StageBatch> batches);

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_STAGE_RULE_H_
