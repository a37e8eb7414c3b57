#include "worker/tile_output.h"

namespace pdsm {

TileOutput::TileOutput(const BakePlan& plan, bool with_preview, PdsmWriter* writer)
    : plan_(plan),
      with_preview_(with_preview),
      writer_(writer),
      preview_(plan.geometry().width, plan.geometry().height) {}

absl::StatusOr<bool> TileOutput::Write(TaskRunner& runner, const std::vector<TileEvents>& parts,
                                       int tile_samples, AssemblyStats* assembly) {
  const TileRect& rect = plan_.tiles[parts.front().tile_index];
  const PdsmTile tile = AssemblePlanTile(plan_, parts, tile_samples, assembly);
  if (with_preview_) {
    absl::StatusOr<std::vector<float>> depth = runner.ReceiverDepth(rect);
    if (!depth.ok()) return depth.status();
    preview_.ShadeTile(tile, *depth);
  }
  std::lock_guard<std::mutex> lock(writer_mu_);
  if (absl::Status s = writer_->WriteTile(tile); !s.ok()) return s;
  return tile.vertices.empty();
}

}  // namespace pdsm
