#include "server/stored_job.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <optional>
#include <string>
#include <utility>

#include <spdlog/spdlog.h>

#include "absl/strings/numbers.h"
#include "absl/strings/str_cat.h"
#include "core/bake/plan_fingerprint.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pipeline/tile_file.h"
#include "core/pipeline/unreached_tile.h"

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

// One light's engine job's output: its calls go to the job with the light they are for. It
// holds the job: the engine may call it after the coordinator has let the job go.
class StoredJob::Light final : public JobOutput {
 public:
  Light(std::shared_ptr<StoredJob> job, const JobLight* light)
      : job_(std::move(job)), light_(light) {}
  void Started() override { job_->Started(); }
  absl::Status StoreTile(const PdsmTile& tile) override { return job_->StoreTile(*light_, tile); }
  absl::Status StoreUnreachedTiles(const BakePlan&, const std::vector<int>& tiles) override {
    return job_->StoreUnreachedTiles(*light_, tiles);
  }
  absl::Status Finish() override { return job_->LightFinished(); }
  absl::Status WithdrawTiles(const std::vector<int>& tile_indices) override {
    return job_->WithdrawTiles(*light_, tile_indices);
  }
  void Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) override {
    job_->LightEnded(*light_, end, status, progress);
  }

 private:
  const std::shared_ptr<StoredJob> job_;
  const JobLight* const light_;  // of *job_
};

StoredJob::StoredJob(JobStore* store, const std::string& data_dir, JobRecord record,
                     pdsm::v1::Scene scene, std::vector<PlannedLight> plans,
                     std::function<void(const std::string&)> on_ended,
                     std::function<void(const absl::Status&)> end_lights, FileSystem* fs)
    : store_(store),
      record_(std::move(record)),
      scene_(std::move(scene)),
      lights_(MakeJobLights(record_.job_id, std::move(plans))),
      paths_(data_dir, record_.job_id),
      on_ended_(std::move(on_ended)),
      end_lights_(std::move(end_lights)),
      fs_(fs),
      light_ends_(lights_.size()) {}

StoredJob::~StoredJob() = default;

std::optional<JobProgress> StoredJob::LightEndProgress(int light) const {
  absl::MutexLock lock(&mu_);
  return light_ends_.at(light);
}

std::shared_ptr<JobOutput> StoredJob::LightOutput(int light) {
  return std::make_shared<Light>(shared_from_this(), &lights_.at(light));
}

std::vector<int> StoredJob::FinishedTiles(int light) const {
  const JobLight& l = lights_.at(light);
  // One read of the folder, not a stat per tile (2^18 of them on the largest job). Only
  // complete files count: "<n>.tile", not a temporary "<n>.tile.tmp-…".
  std::vector<bool> stored(l.plan->tile_count(), false);
  std::error_code ec;
  for (const auto& entry : std::filesystem::directory_iterator(paths_.tiles, ec)) {
    const std::filesystem::path& path = entry.path();
    int index = 0;
    if (path.extension() != ".tile" || !absl::SimpleAtoi(path.stem().string(), &index)) continue;
    index -= l.tile_offset;
    if (index >= 0 && index < static_cast<int>(stored.size())) stored[index] = true;
  }
  // Tiles stored as all lit count too; if the store cannot say which, they are left out (not
  // finished yet, to the caller), never made up.
  absl::StatusOr<std::vector<bool>> all_lit = AllLitTiles();
  if (!all_lit.ok()) {
    spdlog::warn("job {}: cannot read its all-lit tiles: {}", record_.job_id,
                 std::string(all_lit.status().message()));
  }
  std::vector<int> done;
  for (const TileRect& rect : AllTiles(*l.plan)) {
    if (stored[rect.index] || IsUnreachedTile(*l.plan, rect.index) ||
        (all_lit.ok() && (*all_lit)[l.tile_offset + rect.index])) {
      done.push_back(rect.index);
    }
  }
  return done;
}

absl::StatusOr<std::string> StoredJob::FinishedTileFile(int light, int tile) const {
  const JobLight& l = lights_.at(light);
  const std::string path = paths_.Tile(l.tile_offset + tile);
  std::error_code ec;
  if (std::filesystem::exists(path, ec)) return path;
  bool made = tile >= 0 && tile < l.plan->tile_count() && IsUnreachedTile(*l.plan, tile);
  if (!made && tile >= 0 && tile < l.plan->tile_count()) {
    absl::MutexLock lock(&all_lit_mu_);
    absl::StatusOr<const std::vector<bool>*> all_lit = AllLitLocked();
    if (!all_lit.ok()) return all_lit.status();
    made = (**all_lit)[l.tile_offset + tile];
  }
  if (!made) {
    return absl::NotFoundError(
        absl::StrCat("job ", record_.job_id, ": tile ", tile, " is not assembled (yet)"));
  }
  // Two requests at once both write the same bytes; the rename makes either whole.
  std::filesystem::create_directories(paths_.tiles, ec);
  if (absl::Status s =
          WriteTileFile(path, MakeUnreachedTile(*l.plan, tile).tile, l.plan->header.tile_size, fs_);
      !s.ok()) {
    return s;
  }
  return path;
}

void StoredJob::Started() {
  if (started_.exchange(true)) return;  // the first light's first task
  if (absl::Status s = store_->SetState(record_.job_id, pdsm::v1::RUNNING, "", UnixNowMs());
      !s.ok()) {
    spdlog::error("job {}: cannot record RUNNING: {}", record_.job_id, std::string(s.message()));
  }
}

absl::Status StoredJob::StoreTile(const JobLight& light, const PdsmTile& tile) {
  const int tile_in_light = light.plan->TileIndexAt(tile.x0, tile.y0);
  const int index = light.tile_offset + tile_in_light;
  if (IsMadeFromThePlan(*light.plan, tile_in_light, tile)) {
    // All lit: the row alone (one sync, where a file costs three), made again when needed.
    if (ended_) return absl::OkStatus();
    if (absl::Status s = store_->MarkTileDone(record_.job_id, index, UnixNowMs(),
                                              /*all_lit=*/true);
        !s.ok()) {
      return s;
    }
    if (absl::Status s = SetAllLit(index, true); !s.ok()) return s;
    // A file of an earlier run (its row lost in a crash) would only be ignored: remove it.
    FileSystem* fs = fs_ != nullptr ? fs_ : FileSystem::Default();
    const absl::Status removed = fs->RemoveFile(paths_.Tile(index));
    if (!removed.ok() && !absl::IsNotFound(removed)) return removed;
    return absl::OkStatus();
  }
  std::error_code ec;
  std::filesystem::create_directories(paths_.tiles, ec);
  if (absl::Status s = WriteTileFile(paths_.Tile(index), tile, light.plan->header.tile_size, fs_);
      !s.ok())
    return s;
  if (ended_) return absl::OkStatus();  // cancelled meanwhile: the file goes with the folder
  if (absl::Status s = store_->MarkTileDone(record_.job_id, index, UnixNowMs()); !s.ok()) {
    return s;
  }
  if (absl::Status s = SetAllLit(index, false); !s.ok()) return s;
  spdlog::debug("job {} tile {}: stored, {} vertices", record_.job_id, index, tile.vertices.size());
  return absl::OkStatus();
}

bool StoredJob::IsMadeFromThePlan(const BakePlan& plan, int tile_index, const PdsmTile& tile) {
  if (!tile.vertices.empty()) return false;
  const PdsmTile made = MakeUnreachedTile(plan, tile_index).tile;
  return tile.samples == made.samples && tile.offsets == made.offsets;
}

absl::StatusOr<const std::vector<bool>*> StoredJob::AllLitLocked() const {
  if (!all_lit_) {
    absl::StatusOr<std::vector<int>> tiles = store_->AllLitTiles(record_.job_id);
    if (!tiles.ok()) return tiles.status();
    const JobLight& last = lights_.back();
    std::vector<bool> all_lit(last.tile_offset + last.plan->tile_count(), false);
    for (int t : *tiles) {
      if (t >= 0 && t < static_cast<int>(all_lit.size())) all_lit[t] = true;
    }
    all_lit_ = std::move(all_lit);
  }
  return &*all_lit_;
}

absl::StatusOr<std::vector<bool>> StoredJob::AllLitTiles() const {
  absl::MutexLock lock(&all_lit_mu_);
  absl::StatusOr<const std::vector<bool>*> all_lit = AllLitLocked();
  if (!all_lit.ok()) return all_lit.status();
  return **all_lit;
}

absl::Status StoredJob::SetAllLit(int index, bool all_lit) {
  absl::MutexLock lock(&all_lit_mu_);
  absl::StatusOr<const std::vector<bool>*> loaded = AllLitLocked();
  if (!loaded.ok()) return loaded.status();
  (*all_lit_)[index] = all_lit;
  return absl::OkStatus();
}

absl::Status StoredJob::StoreUnreachedTiles(const JobLight& light, const std::vector<int>& tiles) {
  std::vector<int> indices;
  indices.reserve(tiles.size());
  for (int t : tiles) indices.push_back(light.tile_offset + t);
  if (ended_) return absl::OkStatus();
  return store_->MarkTilesDone(record_.job_id, indices, UnixNowMs());
}

absl::Status StoredJob::WithdrawTiles(const JobLight& light, const std::vector<int>& tiles) {
  for (int tile : tiles) {
    const int index = light.tile_offset + tile;
    // The row first: a crash before the file goes leaves a tile a restart recomputes.
    if (absl::Status s = store_->MarkTileUndone(record_.job_id, index); !s.ok()) return s;
    FileSystem* fs = fs_ != nullptr ? fs_ : FileSystem::Default();
    const absl::Status removed = fs->RemoveFile(paths_.Tile(index));
    if (!removed.ok() && !absl::IsNotFound(removed)) return removed;
    if (absl::Status s = SetAllLit(index, false); !s.ok()) return s;
    spdlog::info("job {} tile {}: withdrawn, to be computed again", record_.job_id, index);
  }
  return absl::OkStatus();
}

absl::Status StoredJob::LightFinished() {
  {
    absl::MutexLock lock(&mu_);
    if (++lights_finished_ < static_cast<int>(lights_.size())) return absl::OkStatus();
  }
  return WriteFile();
}

absl::Status StoredJob::WriteFile() {
  std::error_code ec;
  std::filesystem::create_directories(paths_.dir, ec);
  absl::StatusOr<std::vector<bool>> all_lit = AllLitTiles();
  if (!all_lit.ok()) return all_lit.status();
  const auto write_light = [&](const JobLight& light, PdsmWriter* writer) -> absl::Status {
    EmptyTileChunks empty_chunks(light.plan->header.tile_size);
    std::optional<int> unreached_samples;  // UnreachedTileSamples, found at the first use
    const auto tile_of = [&](int64_t index) -> absl::StatusOr<EncodedTile> {
      const int tile = static_cast<int>(index);
      // The stored tiles are copied as they were compressed when they were finished.
      if (!IsUnreachedTile(*light.plan, tile) && !(*all_lit)[light.tile_offset + tile]) {
        return ReadTileChunk(paths_.Tile(light.tile_offset + tile), light.plan->header.tile_size);
      }
      // A tile no caster reaches, or found all lit, was never stored: it is made again, as the
      // engine made it.
      if (!unreached_samples) unreached_samples = UnreachedTileSamples(*light.plan);
      const TileRect rect = light.plan->tile(tile);
      absl::StatusOr<std::string> chunk = empty_chunks.Chunk(rect.width, rect.height);
      if (!chunk.ok()) return chunk.status();
      EncodedTile made{rect.x0, rect.y0, rect.width, rect.height, *unreached_samples, 0, {}};
      made.tile_size = light.plan->header.tile_size;
      made.chunk = *std::move(chunk);
      return made;
    };
    if (absl::Status s = writer->WriteEncodedTiles(tile_of); !s.ok()) return s;
    return writer->Finish();
  };
  if (lights_.size() == 1) {
    absl::StatusOr<std::unique_ptr<PdsmWriter>> writer =
        PdsmWriter::Create(paths_.pdsm, lights_.front().plan->header, fs_);
    if (!writer.ok()) return writer.status();
    return write_light(lights_.front(), writer->get());
  }
  // As the local bake writes it (worker/local_bake.cc): the same parts, the same window.
  int max_width = 1, max_height = 1;
  for (const JobLight& light : lights_) {
    max_width = std::max(max_width, light.plan->geometry().width);
    max_height = std::max(max_height, light.plan->geometry().height);
  }
  absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> writer = PdsmLightsWriter::Create(
      paths_.pdsm, static_cast<int>(lights_.size()), max_width, max_height, fs_);
  if (!writer.ok()) return writer.status();
  for (const JobLight& light : lights_) {
    absl::StatusOr<PdsmWriter*> part = (*writer)->BeginLight(light.plan->header);
    if (!part.ok()) return part.status();
    if (absl::Status s = write_light(light, *part); !s.ok()) return s;
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

void StoredJob::LightEnded(const JobLight& light, JobEnd end, const absl::Status& status,
                           const JobProgress& progress) {
  bool first_failure = false, last = false;
  std::pair<JobEnd, absl::Status> job_end{JobEnd::kSucceeded, absl::OkStatus()};
  int tiles_total = 0;
  {
    absl::MutexLock lock(&mu_);
    light_ends_.at(light.index) = progress;
    tiles_total_ += progress.tiles_total;
    if (end != JobEnd::kSucceeded && !first_failure_) {
      // The job's error names the light when there are several.
      first_failure_.emplace(
          end, lights_.size() == 1
                   ? status
                   : absl::Status(status.code(),
                                  absl::StrCat("light \"", light.name, "\": ", status.message())));
      first_failure = true;
    }
    last = ++lights_ended_ == static_cast<int>(lights_.size());
    if (first_failure_) job_end = *first_failure_;
    tiles_total = tiles_total_;
  }
  // The other lights cannot make the job succeed now: end them (each comes back here).
  if (first_failure && end == JobEnd::kFailed && end_lights_ && lights_.size() > 1) {
    end_lights_(job_end.second);
  }
  if (last) Ended(job_end.first, job_end.second, tiles_total);
}

void StoredJob::Ended(JobEnd end, const absl::Status& status, int tiles_total) {
  const bool recorded = RecordEnd(end, status);
  const std::string& id = record_.job_id;
  std::error_code ec;
  if (end == JobEnd::kSucceeded) {
    // Still RUNNING in the store: the next start rewrites the file from the tiles; keep them.
    if (!recorded) {
      if (on_ended_) on_ended_(id);
      return;
    }
    spdlog::info("job {}: succeeded, {} tiles, PDSM {}", id, tiles_total, paths_.pdsm);
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
