#include "server/stored_job.h"

#include <algorithm>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <iterator>
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
      log((std::filesystem::path(dir) / "tiles.log").string()),
      pdsm((std::filesystem::path(dir) / "pdsm.exr").string()),
      tiles((std::filesystem::path(dir) / "tiles").string()) {}

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
  absl::Status CommitTiles() override { return job_->CommitTiles(); }
  absl::Status StoreUnreachedTiles(const BakePlan&, const std::vector<int>& tiles) override {
    return job_->StoreUnreachedTiles(*light_, tiles);
  }
  absl::Status Finish() override { return job_->BaseFinished(*light_); }
  absl::Status WithdrawTiles(const std::vector<int>& tile_indices) override {
    return job_->WithdrawTiles(*light_, tile_indices);
  }
  void Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) override {
    job_->EngineJobEnded(*light_, end, status, progress, /*level=*/false);
  }

 private:
  const std::shared_ptr<StoredJob> job_;
  const JobLight* const light_;  // of *job_
};

StoredJob::StoredJob(JobStore* store, const std::string& data_dir, JobRecord record,
                     pdsm::v1::Scene scene, std::vector<PlannedLight> plans,
                     std::function<void(const std::string&)> on_ended,
                     std::function<void(const absl::Status&)> end_lights, FileSystem* fs,
                     RefinementHooks refinement)
    : store_(store),
      record_(std::move(record)),
      scene_(std::move(scene)),
      lights_(MakeJobLights(record_.job_id, std::move(plans))),
      paths_(data_dir, record_.job_id),
      on_ended_(std::move(on_ended)),
      end_lights_(std::move(end_lights)),
      fs_(fs),
      refinement_(std::move(refinement)),
      levels_(lights_.size()),
      light_ends_(lights_.size()),
      engine_ends_(lights_.size()) {}

StoredJob::~StoredJob() = default;

std::optional<JobProgress> StoredJob::LightEndProgress(int light) const {
  absl::MutexLock lock(&mu_);
  // While its refinement level runs, a light's progress is its base map's as that ended.
  return light_ends_.at(light) ? light_ends_.at(light) : engine_ends_.at(light).base_progress;
}

std::shared_ptr<JobOutput> StoredJob::LightOutput(int light) {
  return std::make_shared<Light>(shared_from_this(), &lights_.at(light));
}

std::vector<int> StoredJob::FinishedTiles(int light) const {
  const JobLight& l = lights_.at(light);
  std::vector<bool> stored(l.plan->tile_count(), false);
  if (absl::StatusOr<TileLog*> log = Log(); log.ok()) {
    for (int index : (*log)->Tiles()) {
      index -= l.tile_offset;
      if (index >= 0 && index < static_cast<int>(stored.size())) stored[index] = true;
    }
  } else {
    spdlog::warn("job {}: {}", record_.job_id, std::string(log.status().message()));
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

absl::StatusOr<std::string> StoredJob::FinishedTileBytes(int light, int tile) const {
  const JobLight& l = lights_.at(light);
  const auto not_yet = [&] {
    return absl::NotFoundError(
        absl::StrCat("job ", record_.job_id, ": tile ", tile, " is not assembled (yet)"));
  };
  if (tile < 0 || tile >= l.plan->tile_count()) return not_yet();
  // All lit first: the log may still hold a record of what the tile was before.
  absl::StatusOr<bool> made = IsUnstoredTile(l, tile);
  if (!made.ok()) return made.status();
  if (*made) {
    return EncodeTileFile(MakeUnreachedTile(*l.plan, tile).tile, l.plan->header.tile_size,
                          absl::StrCat("job ", record_.job_id, " tile ", tile));
  }
  absl::StatusOr<TileLog*> log = Log();
  if (!log.ok()) return log.status();
  absl::StatusOr<std::string> bytes = (*log)->Read(l.tile_offset + tile);
  if (absl::IsNotFound(bytes.status())) return not_yet();
  return bytes;
}

absl::StatusOr<TileLog*> StoredJob::Log() const {
  absl::MutexLock lock(&log_mu_);
  if (!log_) {
    std::error_code ec;
    std::filesystem::create_directories(paths_.dir, ec);
    absl::StatusOr<std::unique_ptr<TileLog>> log = TileLog::Open(paths_.log, fs_);
    if (!log.ok()) return log.status();
    if (absl::Status s = TakeInTileFiles(log->get()); !s.ok()) return s;
    log_ = *std::move(log);
  }
  return log_.get();
}

absl::Status StoredJob::TakeInTileFiles(TileLog* log) const {
  std::error_code ec;
  if (!std::filesystem::is_directory(paths_.tiles, ec)) return absl::OkStatus();
  // Complete files only: "<n>.tile", not a temporary "<n>.tile.tmp-…".
  int taken = 0;
  for (const auto& entry : std::filesystem::directory_iterator(paths_.tiles, ec)) {
    const std::filesystem::path& path = entry.path();
    int index = 0;
    if (path.extension() != ".tile" || !absl::SimpleAtoi(path.stem().string(), &index) ||
        index < 0) {
      continue;
    }
    std::ifstream in(path, std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.is_open() || in.bad()) {
      spdlog::warn("job {}: cannot read {}: left out", record_.job_id, path.string());
      continue;
    }
    if (absl::Status s = CheckTileFileBytes(bytes, path.string()); !s.ok()) {
      spdlog::warn("job {}: {}: left out", record_.job_id, std::string(s.message()));
      continue;
    }
    if (absl::Status s = log->Append(index, bytes); !s.ok()) return s;
    ++taken;
  }
  if (absl::Status s = log->Sync(); !s.ok()) return s;
  std::filesystem::remove_all(paths_.tiles, ec);
  spdlog::info("job {}: took {} tile files of an earlier build into {}", record_.job_id, taken,
               log->path());
  return absl::OkStatus();
}

absl::StatusOr<std::vector<int>> StoredJob::ResumeTiles(const std::vector<int>& done_tiles) {
  absl::StatusOr<TileLog*> log = Log();
  if (!log.ok()) return log.status();
  absl::StatusOr<std::vector<bool>> all_lit = AllLitTiles();
  if (!all_lit.ok()) return all_lit.status();
  std::vector<bool> done(all_lit->size(), false);
  std::vector<int> kept;
  kept.reserve(done_tiles.size());
  for (const int index : done_tiles) {
    if (index < 0 || index >= static_cast<int>(done.size())) continue;
    done[index] = true;
    const JobLight& light = LightOfTile(index);
    const int tile = index - light.tile_offset;
    if ((*all_lit)[index] || IsUnreachedTile(*light.plan, tile) || (*log)->Has(index)) {
      kept.push_back(index);
      continue;
    }
    spdlog::warn("job {}: tile {} is done but {} has no record of it: computing it again",
                 record_.job_id, index, (*log)->path());
    if (absl::Status s = store_->MarkTileUndone(record_.job_id, index); !s.ok()) return s;
  }
  // Records without a row were never committed, or were withdrawn: they are not the job's.
  for (const int index : (*log)->Tiles()) {
    if (index >= static_cast<int>(done.size()) || !done[index]) (*log)->Forget(index);
  }
  return kept;
}

const JobLight& StoredJob::LightOfTile(int index) const {
  for (const JobLight& light : lights_) {
    if (index < light.tile_offset + light.tile_count()) return light;
  }
  return lights_.back();
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
  absl::StatusOr<TileLog*> log = Log();
  if (!log.ok()) return log.status();
  if (IsMadeFromThePlan(*light.plan, tile_in_light, tile)) {
    // All lit: the row alone, made again when needed.
    if (ended_) return absl::OkStatus();
    (*log)->Forget(index);
    if (absl::Status s = SetAllLit(index, true); !s.ok()) return s;
    AddPending(index, /*all_lit=*/true);
    return absl::OkStatus();
  }
  // Encoded (compressed) here, on the executor's thread; the log only appends.
  absl::StatusOr<std::string> bytes = EncodeTileFile(
      tile, light.plan->header.tile_size, absl::StrCat("job ", record_.job_id, " tile ", index));
  if (!bytes.ok()) return bytes.status();
  if (absl::Status s = (*log)->Append(index, *bytes); !s.ok()) return s;
  if (ended_) return absl::OkStatus();  // cancelled meanwhile: the log goes with the job
  if (absl::Status s = SetAllLit(index, false); !s.ok()) return s;
  AddPending(index, /*all_lit=*/false);
  spdlog::debug("job {} tile {}: stored, {} vertices", record_.job_id, index, tile.vertices.size());
  return absl::OkStatus();
}

void StoredJob::AddPending(int index, bool all_lit) {
  absl::MutexLock lock(&pending_mu_);
  pending_[index] = all_lit;
}

absl::Status StoredJob::CommitTiles() {
  absl::MutexLock commit(&commit_mu_);
  std::map<int, bool> batch;
  {
    absl::MutexLock lock(&pending_mu_);
    batch.swap(pending_);
  }
  if (batch.empty()) return absl::OkStatus();
  std::vector<int> files, all_lit;
  for (const auto& [index, lit] : batch) (lit ? all_lit : files).push_back(index);
  if (!files.empty()) {
    absl::StatusOr<TileLog*> log = Log();
    if (!log.ok()) return log.status();
    if (absl::Status s = (*log)->Sync(); !s.ok()) return s;
  }
  if (ended_) return absl::OkStatus();
  const int64_t now_ms = UnixNowMs();
  if (!files.empty()) {
    if (absl::Status s = store_->MarkTilesDone(record_.job_id, files, now_ms); !s.ok()) return s;
  }
  if (!all_lit.empty()) {
    if (absl::Status s = store_->MarkTilesDone(record_.job_id, all_lit, now_ms, /*all_lit=*/true);
        !s.ok()) {
      return s;
    }
  }
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

absl::StatusOr<bool> StoredJob::IsUnstoredTile(const JobLight& light, int tile) const {
  if (IsUnreachedTile(*light.plan, tile)) return true;
  absl::MutexLock lock(&all_lit_mu_);
  absl::StatusOr<const std::vector<bool>*> all_lit = AllLitLocked();
  if (!all_lit.ok()) return all_lit.status();
  return (**all_lit)[light.tile_offset + tile];
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
  absl::MutexLock commit(&commit_mu_);
  absl::StatusOr<TileLog*> log = Log();
  if (!log.ok()) return log.status();
  for (int tile : tiles) {
    const int index = light.tile_offset + tile;
    {
      absl::MutexLock lock(&pending_mu_);
      pending_.erase(index);
    }
    // The row goes; the record stays in the log, and a restart forgets it (no row).
    if (absl::Status s = store_->MarkTileUndone(record_.job_id, index); !s.ok()) return s;
    (*log)->Forget(index);
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
  absl::StatusOr<TileLog*> log = Log();
  if (!log.ok()) {
    return absl::Status(log.status().code(),
                        absl::StrCat("cannot write ", paths_.pdsm, ": ", log.status().message()));
  }
  const auto write_light = [&](const JobLight& light, PdsmWriter* writer) -> absl::Status {
    EmptyTileChunks empty_chunks(light.plan->header.tile_size);
    std::optional<int> unreached_samples;  // UnreachedTileSamples, found at the first use
    const std::shared_ptr<LightLevel> level = LevelOf(light.index);
    const auto tile_of = [&](int64_t index) -> absl::StatusOr<EncodedTile> {
      const int tile = static_cast<int>(index);
      // A refined tile as spliced (stored_job_levels.cc).
      if (level) {
        if (std::optional<EncodedTile> spliced = SplicedTile(*level, tile)) return *spliced;
      }
      // The stored tiles are copied as they were compressed when they were finished.
      if (!IsUnreachedTile(*light.plan, tile) && !(*all_lit)[light.tile_offset + tile]) {
        absl::StatusOr<std::string> bytes = (*log)->Read(light.tile_offset + tile);
        if (!bytes.ok()) return bytes.status();
        return DecodeTileChunkFile(*bytes, absl::StrCat((*log)->path(), " tile ", index),
                                   light.plan->header.tile_size);
      }
      // A tile no caster reaches, or found all lit, was never stored: it is made again, as the
      // engine made it.
      if (!unreached_samples) unreached_samples = UnreachedTileSamples(*light.plan);
      const TileRect rect = light.plan->tile(tile);
      return empty_chunks.Tile(rect.x0, rect.y0, rect.width, rect.height, *unreached_samples);
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
  std::filesystem::remove(paths_.log, ec);
  std::filesystem::remove_all(paths_.tiles, ec);  // an earlier build's
  if (on_ended_) on_ended_(id);
}

}  // namespace pdsm
