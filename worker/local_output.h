// Where the local bake's tiles go (a JobOutput, core/pipeline/bake_engine.h): compressed as
// they finish, on the thread that finished them, into an EncodedTileStore
// (core/pdsm/encoded_tile_store.h), and copied into the PDSM file when the light is done; and,
// when a preview is asked for, shaded into the preview image from the receivers' depths
// rendered before the bake.
#ifndef PDSM_WORKER_LOCAL_OUTPUT_H_
#define PDSM_WORKER_LOCAL_OUTPUT_H_

#include <atomic>
#include <span>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/status.h"
#include "absl/synchronization/mutex.h"
#include "core/bake/bake_plan.h"
#include "core/pdsm/encoded_tile_store.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/bake_engine.h"
#include "worker/preview_image.h"

namespace pdsm {

class LocalOutput final : public JobOutput {
 public:
  // `plan` and `writer` outlive this. `writer` null: Finish leaves the tiles in tiles(), for
  // the caller to refine (a refined bake's base, worker/local_bake.cc) or read (a refinement
  // level's). `preview_path` empty: no preview. `output_path`: the PDSM's path, beside which
  // the compressed tiles wait for the end of the light. `fs`: where they and the preview are
  // written (null: the real file system).
  LocalOutput(const BakePlan& plan, PdsmWriter* writer, std::string preview_path,
              std::string output_path, FileSystem* fs = nullptr);

  bool has_preview() const { return !preview_path_.empty(); }
  // The preview's surface for tile `tile_index`: the light-space depth of the nearest receiver
  // along each of its rays (TaskRunner::ReceiverDepth), row-major over the tile. Only the
  // pixels the preview samples are kept (PreviewImage::SampledDepths), and only until the tile
  // is shaded. REQUIRES: has_preview(); every tile's set before the bake starts; distinct
  // tiles may be set from different threads.
  void SetReceiverDepth(int tile_index, std::span<const float> depth);

  absl::Status StoreTile(const PdsmTile& tile) override;
  // Without a preview to shade, kept as their rectangles (no tile made and assembled each: a
  // sparse world has 2^18); with one, each through StoreTile.
  absl::Status StoreUnreachedTiles(const BakePlan& plan, const std::vector<int>& tiles) override;
  // Writes the preview, then (with a writer) the PDSM's tiles, then renames the PDSM into place.
  absl::Status Finish() override;
  // The light's tiles as stored: after Finish, all of them.
  EncodedTileStore& tiles() { return tiles_; }
  void Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) override;

  // True once Ended() ran; then status() and progress() hold what it was given.
  bool ended() const { return ended_; }
  absl::Status status() const;
  JobProgress progress() const;

 private:
  const BakePlan& plan_;
  const std::string preview_path_;
  FileSystem* const fs_;
  std::vector<std::vector<float>> receiver_depth_;  // by tile, sampled; dropped once shaded
  PreviewImage preview_;                            // tiles are disjoint: shading needs no lock
  EncodedTileStore tiles_;
  PdsmWriter* const writer_;  // used by Finish() only; null: the caller writes

  mutable absl::Mutex end_mu_;
  std::atomic<bool> ended_{false};
  absl::Status status_ ABSL_GUARDED_BY(end_mu_);
  JobProgress progress_ ABSL_GUARDED_BY(end_mu_);
};

}  // namespace pdsm

#endif  // PDSM_WORKER_LOCAL_OUTPUT_H_
