// Where the local bake's tiles go (a JobOutput, core/pipeline/bake_engine.h): straight into
// the PDSM file as they finish, and, when a preview is asked for, shaded into the preview
// image from the receivers' depths rendered before the bake.
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
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/bake_engine.h"
#include "worker/preview_image.h"

namespace pdsm {

class LocalOutput final : public JobOutput {
 public:
  // `plan` and `writer` outlive this. `preview_path` empty: no preview. `fs`: where the
  // preview is written (null: the real file system).
  LocalOutput(const BakePlan& plan, PdsmWriter* writer, std::string preview_path,
              FileSystem* fs = nullptr);

  bool has_preview() const { return !preview_path_.empty(); }
  // The preview's surface for tile `tile_index`: the light-space depth of the nearest receiver
  // along each of its rays (TaskRunner::ReceiverDepth), row-major over the tile. Only the
  // pixels the preview samples are kept (PreviewImage::SampledDepths), and only until the tile
  // is shaded. REQUIRES: has_preview(); every tile's set before the bake starts; distinct
  // tiles may be set from different threads.
  void SetReceiverDepth(int tile_index, std::span<const float> depth);

  absl::Status StoreTile(const PdsmTile& tile) override;
  absl::Status Finish() override;  // writes the preview, then renames the PDSM into place
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

  absl::Mutex writer_mu_;
  PdsmWriter* const writer_ ABSL_PT_GUARDED_BY(writer_mu_);

  mutable absl::Mutex end_mu_;
  std::atomic<bool> ended_{false};
  absl::Status status_ ABSL_GUARDED_BY(end_mu_);
  JobProgress progress_ ABSL_GUARDED_BY(end_mu_);
};

}  // namespace pdsm

#endif  // PDSM_WORKER_LOCAL_OUTPUT_H_
