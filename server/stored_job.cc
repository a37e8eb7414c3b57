#include "server/stored_job.h"

#include <chrono>
#include <filesystem>

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "core/bake/plan_fingerprint.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/tile_file.h"

namespace pdsm {
namespace {

int64_t UnixNowMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

pdsm::v1::JobState StateOf(JobEnd end) {
  switch (end) {
    case JobEnd::kSucceeded:
      return pdsm::v1::SUCCEEDED;
    case JobEnd::kFailed:
      return pdsm::v1::FAILED;
    case JobEnd::kCancelled:
      return pdsm::v1::CANCELLED;
  }
  return pdsm::v1::FAILED;
}

}  // namespace

JobPaths::JobPaths(const std::string& data_dir, const std::string& job_id)
    : dir((std::filesystem::path(data_dir) / "jobs" / job_id).string()),
      tiles((std::filesystem::path(dir) / "tiles").string()),
      pdsm((std::filesystem::path(dir) / "pdsm.exr").string()) {}

std::string JobPaths::Tile(int tile_index) const {
  return (std::filesystem::path(tiles) / absl::StrCat(tile_index, ".tile")).string();
}

StoredJob::StoredJob(JobStore* store, const std::string& data_dir, JobRecord record,
                     pdsm::v1::Scene scene, std::shared_ptr<const BakePlan> plan,
                     std::function<void(const std::string&)> on_ended, FileSystem* fs)
    : store_(store),
      record_(std::move(record)),
      scene_(std::move(scene)),
      plan_(std::move(plan)),
      fingerprint_(PlanFingerprint(*plan_)),
      paths_(data_dir, record_.job_id),
      on_ended_(std::move(on_ended)),
      fs_(fs) {}

std::vector<int> StoredJob::FinishedTiles() const {
  std::vector<int> done;
  std::error_code ec;
  for (const TileRect& rect : plan_->tiles) {
    if (std::filesystem::exists(paths_.Tile(rect.index), ec)) done.push_back(rect.index);
  }
  return done;
}

void StoredJob::Started() {
  if (absl::Status s = store_->SetState(record_.job_id, pdsm::v1::RUNNING, "", UnixNowMs());
      !s.ok()) {
    spdlog::error("job {}: cannot record RUNNING: {}", record_.job_id, std::string(s.message()));
  }
}

absl::Status StoredJob::StoreTile(const PdsmTile& tile) {
  const int index = plan_->TileIndexAt(tile.x0, tile.y0);
  std::error_code ec;
  std::filesystem::create_directories(paths_.tiles, ec);
  if (absl::Status s = WriteTileFile(paths_.Tile(index), tile, fs_); !s.ok()) return s;
  if (ended_) return absl::OkStatus();  // cancelled meanwhile: the file goes with the folder
  if (absl::Status s = store_->MarkTileDone(record_.job_id, index, UnixNowMs()); !s.ok()) {
    return s;
  }
  spdlog::debug("job {} tile {}: stored, {} vertices", record_.job_id, index, tile.vertices.size());
  return absl::OkStatus();
}

absl::Status StoredJob::Finish() {
  std::error_code ec;
  std::filesystem::create_directories(paths_.dir, ec);
  absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
      PdsmWriter::Create(paths_.pdsm, plan_->header, fs_);
  if (!writer.ok()) return writer.status();
  for (const TileRect& rect : plan_->tiles) {
    absl::StatusOr<PdsmTile> tile = ReadTileFile(paths_.Tile(rect.index));
    if (!tile.ok()) return tile.status();
    if (absl::Status s = (*writer)->WriteTile(*tile); !s.ok()) return s;
  }
  return (*writer)->Finish();
}

bool StoredJob::RecordEnd(JobEnd end, const absl::Status& status) {
  ended_ = true;
  const std::string& id = record_.job_id;
  absl::Status s;
  if (end == JobEnd::kSucceeded) {
    // A crash before this commit leaves the job RUNNING with every tile done: the next start
    // writes the file again from the same tiles.
    std::error_code ec;
    s = store_->SetSucceeded(id, std::filesystem::file_size(paths_.pdsm, ec), UnixNowMs());
  } else {
    s = store_->SetState(id, StateOf(end), std::string(status.message()), UnixNowMs());
  }
  if (!s.ok()) {
    spdlog::error("job {}: cannot record state {}: {}", id, pdsm::v1::JobState_Name(StateOf(end)),
                  std::string(s.message()));
  }
  return s.ok();
}

void StoredJob::Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) {
  const bool recorded = RecordEnd(end, status);
  const std::string& id = record_.job_id;
  std::error_code ec;
  if (end == JobEnd::kSucceeded) {
    // Still RUNNING in the store: the next start rewrites the file from the tiles; keep them.
    if (!recorded) {
      if (on_ended_) on_ended_(id);
      return;
    }
    spdlog::info("job {}: succeeded, {} tiles, PDSM {}", id, progress.tiles_total, paths_.pdsm);
  } else if (end == JobEnd::kFailed) {
    spdlog::error("job {}: failed: {}", id, std::string(status.message()));
  } else {
    spdlog::info("job {}: CANCELLED", id);
    std::filesystem::remove(paths_.pdsm, ec);  // a cancel that won the race keeps no file
  }
  std::filesystem::remove_all(paths_.tiles, ec);
  if (on_ended_) on_ended_(id);
}

}  // namespace pdsm
