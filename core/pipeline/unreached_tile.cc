#include "core/pipeline/unreached_tile.h"

#include <utility>
#include <vector>

#include "core/pipeline/stage_rule.h"
#include "core/pipeline/tile_assembly.h"

namespace pdsm {

bool IsUnreachedTile(const BakePlan& plan, int tile_index) {
  return !plan.tile_has_casters.empty() && !plan.tile_has_casters[tile_index];
}

TileEvents NoShadowEvents(const TileRect& rect) {
  TileEvents none{.tile_index = rect.index,
                  .x0 = rect.x0,
                  .y0 = rect.y0,
                  .width = rect.width,
                  .height = rect.height,
                  .offsets = {},
                  .events = {}};
  none.offsets.assign(none.PixelCount() + 1, 0);
  return none;
}

UnreachedTile MakeUnreachedTile(const BakePlan& plan, int tile_index) {
  const TileEvents none = NoShadowEvents(plan.tile(tile_index));
  std::vector<TileParts> ranges;
  for (size_t k = 0; k < StageRanges(plan.header, 0).size(); ++k) {
    ranges.push_back(TileParts{.in_memory = {none}, .spilled = {}, .shape = none});
  }
  // No run to read back: neither the rule nor the assembly can fail.
  StageVerdict verdict = *JudgeStage(plan.header, TileStageState{}, std::move(ranges), nullptr);
  AssemblyStats stats;
  UnreachedTile out;
  out.tile = *AssemblePlanTile(plan, verdict.events, nullptr, verdict.tile_samples, &stats);
  out.tile_samples = verdict.tile_samples;
  out.samples_skipped = verdict.samples_skipped;
  return out;
}

int UnreachedTileSamples(const BakePlan& plan) { return MakeUnreachedTile(plan, 0).tile.samples; }

}  // namespace pdsm
