// The last step of a local bake, shared by the fixed-count and the adaptive bake: a finished
// tile's batches are assembled (with the tile's receiver windows in a surfaces-only bake),
// shaded into the preview, and written.
#ifndef PDSM_WORKER_TILE_OUTPUT_H_
#define PDSM_WORKER_TILE_OUTPUT_H_

#include <mutex>
#include <vector>

#include "absl/status/statusor.h"
#include "worker/preview_image.h"
#include "core/bake/bake_plan.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/tile_assembly.h"
#include "worker/bake_task.h"

namespace pdsm {

class TileOutput {
 public:
  // `writer` outlives this; the preview is shaded only when `with_preview`.
  TileOutput(const BakePlan& plan, bool with_preview, PdsmWriter* writer);

  // Assembles `parts` (all of one tile's batches) and writes the tile. `tile_samples`: the
  // adaptive tile's sample count, 0 for a fixed-count bake. Returns whether the tile is all lit
  // (no vertex). Thread-safe for different tiles; `runner` belongs to the calling thread.
  absl::StatusOr<bool> Write(TaskRunner& runner, const std::vector<TileEvents>& parts,
                             int tile_samples, AssemblyStats* assembly);

  const PreviewImage& preview() const { return preview_; }

 private:
  const BakePlan& plan_;
  const bool with_preview_;
  PdsmWriter* writer_;
  std::mutex writer_mu_;
  PreviewImage preview_;  // tiles are disjoint: shading needs no lock
};

}  // namespace pdsm

#endif  // PDSM_WORKER_TILE_OUTPUT_H_
