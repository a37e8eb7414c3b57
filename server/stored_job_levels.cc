// A stored job's refinement levels (adaptive resolution in the service; server/stored_job.h
// says how they run, docs/algorithms.md section 10 what they compute). The same pass as the
// local bake's (worker/local_bake.cc, RefineLight): the same selection from the same base
// tiles, the same level plan, the same splice, so that the file is the local bake's bytes.
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "core/bake/refined_pixels_codec.h"
#include "core/pdsm/encoded_tile_store.h"
#include "core/pipeline/refinement_pass.h"
#include "core/pipeline/tile_file.h"
#include "core/pipeline/unreached_tile.h"
#include "server/job_admission.h"
#include "server/stored_job.h"

namespace pdsm {

struct StoredJob::LightLevel {
  LightLevel(PlannedLight planned, std::string engine, std::string refined, FileSystem* fs,
             const std::string& pdsm_path)
      : pixels(planned.plan->refined->count()),
        plan(std::move(planned.plan)),
        fingerprint(std::move(planned.fingerprint)),
        engine_id(std::move(engine)),
        refined_pixels(std::make_shared<const std::string>(std::move(refined))),
        tiles(plan->header, pdsm_path, fs),
        stored(plan->tile_count(), false) {}

  const int64_t pixels;  // refined
  const std::shared_ptr<const BakePlan> plan;
  const std::string fingerprint;
  const std::string engine_id;
  const std::shared_ptr<const std::string> refined_pixels;  // EncodeRefinedPixels
  // The level's tiles, in a scratch file beside the PDSM (gone with the process: a restart
  // bakes the level again).
  EncodedTileStore tiles;

  absl::Mutex mu;
  std::vector<bool> stored ABSL_GUARDED_BY(mu);  // by level tile: put once, then replaced
  // The base tiles with refined pixels, spliced and encoded, by the light's tile index: a
  // tile's chunk, as EncodedTileStore::Replace encodes it in the local bake.
  std::map<int, EncodedTile> spliced ABSL_GUARDED_BY(mu);
};

namespace {

// A spliced tile in StoredJob::LightLevel::spliced: its chunk and its map node.
int64_t SplicedHeldBytes(const EncodedTile& tile) {
  constexpr int64_t kMapNodeBytes = 4 * sizeof(void*);  // std::map's links and colour
  return kMapNodeBytes + static_cast<int64_t>(sizeof(int) + sizeof(EncodedTile)) +
         static_cast<int64_t>(tile.chunk.capacity());
}

}  // namespace

// What `level` holds when it starts: its plan, refined pixels and engine job
// (LightHeldBytes), the pixels' encoding FetchRefinement hands out, and the per-tile records
// of its scratch store and of which tiles are stored.
int64_t StoredJob::LevelHeldBytes(const LightLevel& level) {
  const int64_t tiles = level.plan->tile_count();
  return static_cast<int64_t>(sizeof(LightLevel)) + LightHeldBytes(*level.plan) +
         static_cast<int64_t>(level.refined_pixels->capacity()) +
         tiles * EncodedTileStore::kHeldBytesPerTile + (tiles + 7) / 8;
}

// The level's engine job's output. It holds the job, as Light does.
class StoredJob::LevelOutput final : public JobOutput {
 public:
  LevelOutput(std::shared_ptr<StoredJob> job, const JobLight* light,
              std::shared_ptr<LightLevel> level)
      : job_(std::move(job)), light_(light), level_(std::move(level)) {}

  absl::Status StoreTile(const PdsmTile& tile) override {
    const int index = level_->plan->TileIndexAt(tile.x0, tile.y0);
    return FirstStore(index) ? level_->tiles.Put(tile) : level_->tiles.Replace(tile);
  }
  // As the local bake keeps them: a tile without vertices, carrying the samples.
  absl::Status StoreUnreachedTiles(const BakePlan& plan, const std::vector<int>& tiles) override {
    const int samples = UnreachedTileSamples(plan);
    for (const int t : tiles) {
      const TileRect rect = plan.tile(t);
      if (!FirstStore(t)) continue;  // stored before: it is the same
      if (absl::Status s = level_->tiles.PutWithoutVertices(rect.x0, rect.y0, samples); !s.ok()) {
        return s;
      }
    }
    return absl::OkStatus();
  }
  // Not durable, on purpose: the level is chosen and baked again after a restart.
  absl::Status CommitTiles() override { return absl::OkStatus(); }
  // A withdrawn tile is recomputed and stored again, in place of this one (StoreTile).
  absl::Status WithdrawTiles(const std::vector<int>&) override { return absl::OkStatus(); }
  absl::Status Finish() override { return job_->LevelFinished(*light_); }
  void Ended(JobEnd end, const absl::Status& status, const JobProgress& progress) override {
    job_->EngineJobEnded(*light_, end, status, progress, /*level=*/true);
  }

 private:
  // Whether tile `index` is stored for the first time (then Put, else Replace).
  bool FirstStore(int index) {
    absl::MutexLock lock(&level_->mu);
    const bool first = !level_->stored[index];
    level_->stored[index] = true;
    return first;
  }

  const std::shared_ptr<StoredJob> job_;
  const JobLight* const light_;  // of *job_
  const std::shared_ptr<LightLevel> level_;
};

std::vector<std::string> StoredJob::EngineIds() const {
  std::vector<std::string> ids;
  for (const JobLight& light : lights_) ids.push_back(light.engine_id);
  absl::MutexLock lock(&levels_mu_);
  for (const std::shared_ptr<LightLevel>& level : levels_) {
    if (level) ids.push_back(level->engine_id);
  }
  return ids;
}

std::shared_ptr<StoredJob::LightLevel> StoredJob::LevelOf(int light) const {
  absl::MutexLock lock(&levels_mu_);
  return light >= 0 && light < static_cast<int>(levels_.size()) ? levels_[light] : nullptr;
}

absl::StatusOr<StoredJob::LevelInfo> StoredJob::Level(int light) const {
  const std::shared_ptr<LightLevel> level = LevelOf(light);
  if (!level || ended_) {
    return absl::FailedPreconditionError(absl::StrCat("job ", record_.job_id, ": light ", light,
                                                      " has no refinement level running"));
  }
  return LevelInfo{level->engine_id, level->fingerprint, level->refined_pixels,
                   level->plan->refinement, level->pixels};
}

std::optional<EncodedTile> StoredJob::SplicedTile(LightLevel& level, int tile) {
  absl::MutexLock lock(&level.mu);
  const auto it = level.spliced.find(tile);
  if (it == level.spliced.end()) return std::nullopt;
  return it->second;
}

absl::StatusOr<PdsmTile> StoredJob::BaseTile(const JobLight& light, int tile) const {
  absl::StatusOr<bool> made = IsUnstoredTile(light, tile);
  if (!made.ok()) return made.status();
  // As the engine made it (and the local bake stored it).
  if (*made) return MakeUnreachedTile(*light.plan, tile).tile;
  absl::StatusOr<TileLog*> log = Log();
  if (!log.ok()) return log.status();
  const int index = light.tile_offset + tile;
  absl::StatusOr<std::string> bytes = (*log)->Read(index);
  if (!bytes.ok()) return bytes.status();
  return DecodeTileFile(*bytes, absl::StrCat((*log)->path(), " tile ", index));
}

absl::Status StoredJob::BaseFinished(const JobLight& light) {
  if (light.plan->header.max_refinement <= 1) return LightFinished();
  return BeginLevel(light);
}

absl::Status StoredJob::BeginLevel(const JobLight& light) {
  const std::string label =
      lights_.size() == 1 ? absl::StrCat("job ", record_.job_id)
                          : absl::StrCat("job ", record_.job_id, " light \"", light.name, "\"");
  if (!refinement_.plan_level || !refinement_.start_level) {
    return absl::InternalError(absl::StrCat(label, ": bake.maxRefinement ",
                                            light.plan->header.max_refinement,
                                            ", but this job was made without refinement hooks"));
  }
  absl::StatusOr<std::shared_ptr<const RefinedPixels>> refined = SelectRefinedPixels(
      *light.plan, [&](int t) { return BaseTile(light, t); }, refinement_.threads);
  if (!refined.ok()) return refined.status();
  if ((*refined)->empty()) {
    spdlog::info("{}: no pixel to refine", label);
    return LightFinished();
  }
  absl::StatusOr<PlannedLight> planned = refinement_.plan_level(light.index, *refined);
  if (!planned.ok()) return planned.status();
  auto level = std::make_shared<LightLevel>(*std::move(planned), LevelEngineJobId(light.engine_id),
                                            EncodeRefinedPixels(**refined), fs_, paths_.pdsm);
  if (refinement_.hold) refinement_.hold(LevelHeldBytes(*level));
  {
    absl::MutexLock lock(&levels_mu_);
    levels_[light.index] = level;
  }
  // A cancel that came while the pixels were chosen: no level. (One that comes between here
  // and the engine taking the level ends the light as cancelled when the level ends.)
  if (ended_) return absl::CancelledError(absl::StrCat(label, ": ended before its level"));
  // Before the level can end: the light now ends with the later of its two engine jobs.
  {
    absl::MutexLock lock(&mu_);
    ++engine_ends_[light.index].pending;
  }
  spdlog::info("{}: refining {} pixels {}x: level {}, {} tiles", label, (*refined)->count(),
               (*refined)->factor(), level->engine_id, level->plan->tile_count());
  const absl::Status started =
      refinement_.start_level(level->engine_id, level->plan,
                              std::make_shared<LevelOutput>(shared_from_this(), &light, level));
  if (!started.ok()) {
    absl::MutexLock lock(&mu_);
    --engine_ends_[light.index].pending;
  }
  return started;
}

absl::Status StoredJob::LevelFinished(const JobLight& light) {
  const std::shared_ptr<LightLevel> level = LevelOf(light.index);
  if (!level) return absl::InternalError(absl::StrCat("job ", record_.job_id, ": no level"));
  const int tile_size = light.plan->header.tile_size;
  const LevelTileSource level_tile = [&](int t) -> absl::StatusOr<std::optional<PdsmTile>> {
    const TileRect rect = level->plan->tile(t);
    absl::StatusOr<PdsmTile> tile = level->tiles.Get(rect.x0, rect.y0);
    if (!tile.ok()) return tile.status();
    return std::optional<PdsmTile>(*std::move(tile));
  };
  const auto keep = [&](const PdsmTile& tile) -> absl::Status {
    absl::StatusOr<EncodedTile> encoded = EncodeTileChunk(tile, tile_size);
    if (!encoded.ok()) return encoded.status();
    const int index = light.plan->TileIndexAt(tile.x0, tile.y0);
    absl::MutexLock lock(&level->mu);
    level->spliced[index] = *std::move(encoded);
    return absl::OkStatus();
  };
  if (absl::Status s = SpliceRefinedTiles(
          *light.plan, *level->plan, [&](int t) { return BaseTile(light, t); }, level_tile, keep,
          refinement_.threads);
      !s.ok()) {
    return s;
  }
  if (refinement_.hold) {
    int64_t spliced = 0;
    {
      absl::MutexLock lock(&level->mu);
      for (const auto& [index, tile] : level->spliced) spliced += SplicedHeldBytes(tile);
    }
    refinement_.hold(spliced);
  }
  return LightFinished();
}

void StoredJob::EngineJobEnded(const JobLight& light, JobEnd end, const absl::Status& status,
                               const JobProgress& progress, bool level) {
  bool last = false, first_failure = false;
  std::optional<std::pair<JobEnd, absl::Status>> failure;
  JobProgress light_progress = progress;
  {
    absl::MutexLock lock(&mu_);
    EngineEnds& ends = engine_ends_.at(light.index);
    if (!level) ends.base_progress = progress;
    if (end != JobEnd::kSucceeded && !ends.failure) {
      ends.failure.emplace(end, status);
      first_failure = true;
    }
    last = --ends.pending == 0;
    failure = ends.failure;
    // The light's tiles and samples are its base map's.
    if (ends.base_progress) light_progress = *ends.base_progress;
  }
  if (!last) {
    // Its other engine job cannot make the light succeed now (a cancel reaches every one).
    if (first_failure && end == JobEnd::kFailed && end_lights_) end_lights_(status);
    return;
  }
  if (failure) {
    LightEnded(light, failure->first, failure->second, light_progress);
  } else {
    LightEnded(light, JobEnd::kSucceeded, absl::OkStatus(), light_progress);
  }
}

}  // namespace pdsm
