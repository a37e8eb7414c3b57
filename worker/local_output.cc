#include "worker/local_output.h"

#include <span>
#include <utility>
#include <vector>

#include "core/pipeline/unreached_tile.h"

namespace pdsm {

LocalOutput::LocalOutput(const BakePlan& plan, PdsmWriter* writer, std::string preview_path,
                         std::string output_path, FileSystem* fs)
    : plan_(plan),
      preview_path_(std::move(preview_path)),
      fs_(fs),
      receiver_depth_(has_preview() ? plan.tile_count() : 0),
      preview_(has_preview() ? plan.geometry().width : 0,
               has_preview() ? plan.geometry().height : 0),
      tiles_(plan.header, std::move(output_path), fs),
      writer_(writer) {}

void LocalOutput::SetReceiverDepth(int tile_index, std::span<const float> depth) {
  const TileRect rect = plan_.tile(tile_index);
  receiver_depth_.at(tile_index) =
      preview_.SampledDepths(rect.x0, rect.y0, rect.width, rect.height, depth);
}

absl::Status LocalOutput::StoreTile(const PdsmTile& tile) {
  if (has_preview()) {
    std::vector<float>& depth = receiver_depth_.at(plan_.TileIndexAt(tile.x0, tile.y0));
    preview_.ShadeTile(tile, depth);
    std::vector<float>().swap(depth);  // each tile is stored once
  }
  return tiles_.Put(tile);
}

absl::Status LocalOutput::StoreUnreachedTiles(const BakePlan& plan, const std::vector<int>& tiles) {
  if (has_preview()) return JobOutput::StoreUnreachedTiles(plan, tiles);
  const int samples = UnreachedTileSamples(plan);
  for (const int t : tiles) {
    const TileRect rect = plan.tile(t);
    if (absl::Status s = tiles_.PutWithoutVertices(rect.x0, rect.y0, samples); !s.ok()) return s;
  }
  return absl::OkStatus();
}

absl::Status LocalOutput::Finish() {
  if (has_preview()) {
    if (absl::Status s = preview_.Write(preview_path_, fs_); !s.ok()) return s;
  }
  if (writer_ == nullptr) return absl::OkStatus();
  if (absl::Status s = tiles_.WriteTo(writer_); !s.ok()) return s;
  return writer_->Finish();
}

void LocalOutput::Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) {
  absl::MutexLock lock(&end_mu_);
  status_ = end == JobEnd::kSucceeded ? absl::OkStatus() : status;
  progress_ = progress;
  ended_ = true;
}

absl::Status LocalOutput::status() const {
  absl::MutexLock lock(&end_mu_);
  return status_;
}

JobProgress LocalOutput::progress() const {
  absl::MutexLock lock(&end_mu_);
  return progress_;
}

}  // namespace pdsm
