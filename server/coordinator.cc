#include "server/coordinator.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <optional>
#include <random>

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "core/assets/mesh_asset.h"
#include "core/bake/adaptive_sampling.h"
#include "core/bake/plan_fingerprint.h"
#include "core/pdsm/pdsm_file.h"
#include "core/pdsm/pdsm_query.h"
#include "core/scene/scene_loader.h"
#include "rpc/tile_events_codec.h"
#include "core/pipeline/tile_assembly.h"
#include "core/pipeline/tile_file.h"

namespace pdsm {
namespace {

constexpr int64_t kTickMs = 250;
constexpr int64_t kRateWindowMs = 60'000;

std::string RandomHex(int bytes) {
  static std::mutex mu;
  static std::random_device device;
  std::lock_guard<std::mutex> lock(mu);
  std::string out;
  for (int i = 0; i < bytes; ++i) out += absl::StrFormat("%02x", device() & 0xff);
  return out;
}

bool IsTerminal(pdsm::v1::JobState state) {
  return state == pdsm::v1::SUCCEEDED || state == pdsm::v1::FAILED ||
         state == pdsm::v1::CANCELLED;
}

absl::Status CheckIdempotencyKey(const std::string& key) {
  if (key.empty() || key.size() > 128) {
    return absl::InvalidArgumentError(absl::StrCat(
        "idempotency_key: must have 1 to 128 characters (got ", key.size(), ")"));
  }
  for (char c : key) {
    if (c < 0x21 || c > 0x7e) {
      return absl::InvalidArgumentError("idempotency_key: must be printable ASCII, no spaces");
    }
  }
  return absl::OkStatus();
}

}  // namespace

// A job the scheduler is working on: its plan and the partial results of its open tiles.
struct Coordinator::ActiveJob {
  JobRecord record;
  pdsm::v1::Scene scene;
  BakePlan plan;
  std::string fingerprint;
  // Open tiles: (sample_begin, events) of each accepted batch.
  std::map<int, std::vector<std::pair<int, TileEvents>>> parts;
  // Adaptive jobs: each open tile's stage and the merged events of its earlier stages.
  struct AdaptiveTile {
    int stage = 0;
    std::vector<TileEvents> before;  // empty or one merged list
  };
  std::map<int, AdaptiveTile> adaptive;
  int tiles_done = 0;
  int64_t samples_done = 0;        // samples x tiles covered by accepted results
  int64_t samples_at_resume = 0;   // for the ETA: progress made by this process only
  int64_t resumed_ms = 0;
  bool running = false;            // RUNNING written to the store
  std::atomic<bool> ended{false};   // cancelled, failed or finished: drop late work
};

Coordinator::Coordinator(const CoordinatorOptions& options)
    : options_(options),
      scheduler_(SchedulerOptions{
          .lease_ms = options.lease_ms,
          .max_task_failures = options.max_task_failures,
          .max_worker_failures_per_job = options.max_worker_failures,
          .max_open_tiles = options.max_open_tiles,
          // A fresh random base: results for a previous process's leases can never match.
          .lease_id_base = (std::stoull(RandomHex(4), nullptr, 16) << 32) | 1,
      }) {}

absl::StatusOr<std::unique_ptr<Coordinator>> Coordinator::Start(
    const CoordinatorOptions& options) {
  std::unique_ptr<Coordinator> c(new Coordinator(options));
  c->started_ms_ = c->NowMs();
  absl::StatusOr<std::unique_ptr<JobStore>> store = JobStore::Open(options.data_dir);
  if (!store.ok()) return store.status();
  c->store_ = *std::move(store);
  absl::StatusOr<std::unique_ptr<AssetStore>> assets =
      AssetStore::Open((std::filesystem::path(options.data_dir) / "assets").string());
  if (!assets.ok()) return assets.status();
  c->assets_ = *std::move(assets);
  for (int i = 0; i < std::max(1, options.assembly_threads); ++i) {
    c->pool_.emplace_back([p = c.get()] { p->PoolLoop(); });
  }
  if (absl::Status s = c->Resume(); !s.ok()) return s;
  c->ticker_ = std::thread([p = c.get()] { p->TickLoop(); });
  return c;
}

Coordinator::~Coordinator() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  tick_cv_.notify_all();
  if (ticker_.joinable()) ticker_.join();
  {
    std::lock_guard<std::mutex> lock(pool_mu_);
    pool_stopping_ = true;
  }
  pool_cv_.notify_all();
  for (std::thread& t : pool_) t.join();
}

int64_t Coordinator::NowMs() const {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

std::string Coordinator::JobDir(const std::string& job_id) const {
  return (std::filesystem::path(options_.data_dir) / "jobs" / job_id).string();
}

std::string Coordinator::TilesDir(const std::string& job_id) const {
  return (std::filesystem::path(JobDir(job_id)) / "tiles").string();
}

std::string Coordinator::TilePath(const std::string& job_id, int tile_index) const {
  return (std::filesystem::path(TilesDir(job_id)) / absl::StrCat(tile_index, ".tile")).string();
}

// ---- Pool and ticker -------------------------------------------------------------------

void Coordinator::Post(std::function<void()> work) {
  {
    std::lock_guard<std::mutex> lock(pool_mu_);
    pool_queue_.push_back(std::move(work));
  }
  pool_cv_.notify_one();
}

void Coordinator::PoolLoop() {
  for (;;) {
    std::function<void()> work;
    {
      std::unique_lock<std::mutex> lock(pool_mu_);
      pool_cv_.wait(lock, [&] { return pool_stopping_ || !pool_queue_.empty(); });
      // Unfinished work is safe to drop: everything not yet durable is redone on restart.
      if (pool_stopping_) return;
      work = std::move(pool_queue_.front());
      pool_queue_.pop_front();
    }
    work();
  }
}

void Coordinator::TickLoop() {
  std::unique_lock<std::mutex> lock(mu_);
  while (!stopping_) {
    tick_cv_.wait_for(lock, std::chrono::milliseconds(kTickMs));
    if (stopping_) break;
    const int64_t now = NowMs();
    std::vector<JobFailure> failures = scheduler_.Tick(now);
    while (!recent_results_.empty() && recent_results_.front().first < now - kRateWindowMs) {
      recent_results_.pop_front();
    }
    lock.unlock();
    for (const JobFailure& f : failures) EndJob(f.job_id, pdsm::v1::FAILED, f.reason);
    lock.lock();
  }
}

// ---- Jobs: admission, resumption, ending -----------------------------------------------

absl::StatusOr<BakePlan> Coordinator::PlanFromScene(const pdsm::v1::Scene& scene,
                                                    const std::string& label,
                                                    bool enforce_limits) const {
  // Asset triangles are counted as they decode, to stop early on a huge scene; the final
  // check counts every mesh (inline ones too) once.
  int64_t asset_triangles = 0;
  const MeshAssetResolver resolver =
      [&](const std::string& sha256, const std::string& context)
      -> absl::StatusOr<MeshFileData> {
    absl::StatusOr<std::string> blob = assets_->Get(sha256);
    if (absl::IsNotFound(blob.status())) {
      return absl::FailedPreconditionError(
          absl::StrCat(context, ": asset ", sha256, " has not been uploaded"));
    }
    if (!blob.ok()) return blob.status();
    absl::StatusOr<MeshFileData> mesh = DecodeMeshAsset(*blob, context);
    if (!mesh.ok()) return mesh.status();
    asset_triangles += static_cast<int64_t>(mesh->indices.size() / 3);
    if (enforce_limits && asset_triangles > options_.max_triangles) {
      return absl::ResourceExhaustedError(absl::StrCat(
          context, ": the scene exceeds this coordinator's limit of ", options_.max_triangles,
          " triangles"));
    }
    return mesh;
  };
  absl::StatusOr<Scene> loaded = SceneFromProto(scene, label, /*base_dir=*/"", resolver);
  if (!loaded.ok()) return loaded.status();
  if (enforce_limits) {
    int64_t triangles = 0;
    for (const TriangleMesh& m : loaded->meshes) triangles += m.indices.size() / 3;
    const int64_t pixels = int64_t{loaded->bake.width} * loaded->bake.height;
    if (pixels > options_.max_job_pixels) {
      return absl::ResourceExhaustedError(absl::StrFormat(
          "%s: bake.resolution: %dx%d is %d pixels, above this coordinator's limit of %d",
          label, loaded->bake.width, loaded->bake.height, pixels, options_.max_job_pixels));
    }
    if (loaded->bake.samples > options_.max_samples) {
      return absl::ResourceExhaustedError(
          absl::StrFormat("%s: bake.samples: %d is above this coordinator's limit of %d", label,
                          loaded->bake.samples, options_.max_samples));
    }
    if (triangles > options_.max_triangles) {
      return absl::ResourceExhaustedError(
          absl::StrFormat("%s: meshes: %d triangles, above this coordinator's limit of %d",
                          label, triangles, options_.max_triangles));
    }
  }
  return PlanBake(*loaded);
}

absl::StatusOr<pdsm::v1::Job> Coordinator::SubmitBake(
    const pdsm::v1::SubmitBakeRequest& request) {
  if (absl::Status s = CheckIdempotencyKey(request.idempotency_key()); !s.ok()) return s;
  if (request.priority() < -1000 || request.priority() > 1000) {
    return absl::InvalidArgumentError(
        absl::StrCat("priority: must be in [-1000, 1000] (got ", request.priority(), ")"));
  }
  absl::StatusOr<BakePlan> plan = PlanFromScene(request.scene(), "scene", true);
  if (!plan.ok()) return plan.status();

  JobRecord record;
  record.job_id = RandomHex(8);
  record.idempotency_key = request.idempotency_key();
  record.scene_name = request.scene().name();
  record.state = pdsm::v1::QUEUED;
  record.priority = request.priority();
  record.tiles_total = static_cast<int>(plan->tiles.size());
  record.samples_total = int64_t{plan->header.samples} * record.tiles_total;
  record.created_unix_ms = record.updated_unix_ms = NowMs();
  record.width = plan->geometry().width;
  record.height = plan->geometry().height;
  record.samples = plan->header.samples;
  if (!request.scene().SerializeToString(&record.scene)) {
    return absl::InternalError("cannot serialize the scene");
  }
  bool created = false;
  absl::StatusOr<JobRecord> stored = store_->CreateJob(record, &created);
  if (!stored.ok()) return stored.status();
  if (created) {
    spdlog::info("job {}: submitted \"{}\", {}x{}, {} samples, {} tiles, priority {}",
                 stored->job_id, stored->scene_name, stored->width, stored->height,
                 stored->samples, stored->tiles_total, stored->priority);
    if (absl::Status s = Activate(*stored, {}, *std::move(plan)); !s.ok()) return s;
  }
  return GetJob(stored->job_id);
}

absl::StatusOr<std::shared_ptr<Coordinator::ActiveJob>> Coordinator::LoadActive(
    const JobRecord& record, std::optional<BakePlan> plan) {
  auto job = std::make_shared<ActiveJob>();
  job->record = record;
  if (!job->scene.ParseFromString(record.scene)) {
    return absl::DataLossError(absl::StrCat("job ", record.job_id, ": stored scene is corrupt"));
  }
  if (!plan) {
    absl::StatusOr<BakePlan> planned =
        PlanFromScene(job->scene, absl::StrCat("job ", record.job_id), false);
    if (!planned.ok()) return planned.status();
    plan = *std::move(planned);
  }
  job->plan = *std::move(plan);
  job->fingerprint = PlanFingerprint(job->plan);
  job->running = record.state == pdsm::v1::RUNNING;
  return job;
}

absl::Status Coordinator::Activate(const JobRecord& record, const std::vector<int>& done_tiles,
                                   std::optional<BakePlan> plan) {
  absl::StatusOr<std::shared_ptr<ActiveJob>> job = LoadActive(record, std::move(plan));
  if (!job.ok()) return job.status();
  std::vector<bool> done((*job)->plan.tiles.size(), false);
  for (int t : done_tiles) {
    if (t >= 0 && t < static_cast<int>(done.size())) done[t] = true;
  }
  JobSpec spec;
  spec.job_id = record.job_id;
  spec.priority = record.priority;
  spec.sequence = record.sequence;
  spec.samples = (*job)->plan.header.samples;
  spec.samples_per_task = std::max(1, options_.samples_per_task);
  if ((*job)->plan.header.adaptive()) {
    spec.adaptive_min_samples = std::max(1, (*job)->plan.header.adaptive_min_samples);
  }
  for (size_t t = 0; t < done.size(); ++t) {
    if (!done[t]) spec.tiles.push_back(static_cast<int>(t));
  }
  (*job)->tiles_done = static_cast<int>(done.size() - spec.tiles.size());
  (*job)->samples_done = int64_t{(*job)->tiles_done} * spec.samples;
  (*job)->samples_at_resume = (*job)->samples_done;
  (*job)->resumed_ms = NowMs();
  bool complete = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    scheduler_.AddJob(spec);
    active_[record.job_id] = *job;
    complete = scheduler_.JobComplete(record.job_id);
  }
  if (complete) Post([this, j = *job] { FinishJob(j); });
  return absl::OkStatus();
}

absl::Status Coordinator::Resume() {
  absl::StatusOr<std::vector<JobRecord>> jobs = store_->UnfinishedJobs();
  if (!jobs.ok()) return jobs.status();
  for (const JobRecord& record : *jobs) {
    absl::StatusOr<std::vector<int>> done = store_->DoneTiles(record.job_id);
    if (!done.ok()) return done.status();
    if (absl::Status s = Activate(record, *done, std::nullopt); !s.ok()) {
      // One unreadable job must not keep the others from resuming.
      spdlog::error("job {}: cannot resume: {}", record.job_id, std::string(s.message()));
      if (absl::Status f = store_->SetState(record.job_id, pdsm::v1::FAILED,
                                            absl::StrCat("cannot resume: ", s.message()),
                                            NowMs());
          !f.ok()) {
        return f;
      }
      continue;
    }
    spdlog::info("job {}: resumed with {} of {} tiles done", record.job_id, done->size(),
                 record.tiles_total);
  }
  return absl::OkStatus();
}

void Coordinator::EndJob(const std::string& job_id, pdsm::v1::JobState state,
                         const std::string& error) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = active_.find(job_id);
    if (it == active_.end()) return;  // already ended
    it->second->ended = true;
    active_.erase(it);
    scheduler_.RemoveJob(job_id);
  }
  if (state == pdsm::v1::FAILED) {
    spdlog::error("job {}: failed: {}", job_id, error);
  } else {
    spdlog::info("job {}: {}", job_id, pdsm::v1::JobState_Name(state));
  }
  if (absl::Status s = store_->SetState(job_id, state, error, NowMs()); !s.ok()) {
    spdlog::error("job {}: cannot record state {}: {}", job_id, pdsm::v1::JobState_Name(state),
                  std::string(s.message()));
  }
  std::error_code ec;
  std::filesystem::remove_all(TilesDir(job_id), ec);
}

absl::StatusOr<pdsm::v1::Job> Coordinator::CancelJob(const std::string& job_id) {
  absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
  if (!record.ok()) return record.status();
  if (!IsTerminal(record->state)) EndJob(job_id, pdsm::v1::CANCELLED, "cancelled by request");
  return GetJob(job_id);
}

// ---- Tiles and the final file ----------------------------------------------------------

void Coordinator::JudgeStage(std::shared_ptr<ActiveJob> job, int tile_index,
                             std::vector<std::pair<int, TileEvents>> parts) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (job->ended) return;
  }
  const PdsmHeader& h = job->plan.header;
  ActiveJob::AdaptiveTile state;
  {
    std::lock_guard<std::mutex> lock(mu_);
    state = std::move(job->adaptive[tile_index]);
  }
  // Merge each range of the stage, then the decision the local bake makes too
  // (JudgeAdaptiveStage, core/bake/adaptive_sampling.h).
  const std::vector<SampleRange> ranges =
      AdaptiveStageRanges(state.stage, std::max(1, h.adaptive_min_samples), h.samples);
  std::vector<TileEvents> range_results;
  for (const SampleRange& range : ranges) {
    std::vector<TileEvents> range_parts;
    for (auto& [begin, events] : parts) {
      if (begin >= range.begin && begin < range.end) range_parts.push_back(std::move(events));
    }
    range_results.push_back(MergeTileEvents(range_parts));
  }
  const int samples = ranges.back().end;
  if (JudgeAdaptiveStage(h, ranges, std::move(range_results), &state.before)) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      job->adaptive.erase(tile_index);
      // Progress counts samples out of tiles x maximum: the ones a converged tile skips are
      // done too, so a finished job reads 1.
      job->samples_done += h.samples - samples;
    }
    std::vector<std::pair<int, TileEvents>> all;
    all.emplace_back(0, std::move(state.before.front()));
    return AssembleAndStore(job, tile_index, std::move(all), samples);
  }
  ++state.stage;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (job->ended) return;
    job->adaptive[tile_index] = std::move(state);
    if (scheduler_.AddStage(job->record.job_id, tile_index)) return;
  }
  // A tile left open would hold its slot and the job would never end: fail it loudly.
  EndJob(job->record.job_id, pdsm::v1::FAILED,
         absl::StrCat("tile ", tile_index, ": its next adaptive stage could not be queued"));
}

void Coordinator::AssembleAndStore(std::shared_ptr<ActiveJob> job, int tile_index,
                                   std::vector<std::pair<int, TileEvents>> parts,
                                   int tile_samples) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (job->ended) return;  // cancelled or failed while queued
  }
  // Batches in sample order: the merge does not depend on it, but a fixed order costs nothing.
  std::sort(parts.begin(), parts.end(),
            [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<TileEvents> events;
  events.reserve(parts.size());
  for (auto& [begin, e] : parts) events.push_back(std::move(e));
  AssemblyStats stats;
  const PdsmTile tile = AssemblePlanTile(job->plan, events, tile_samples, &stats);
  events.clear();

  const std::string& id = job->record.job_id;
  const std::string path = TilePath(id, tile_index);
  std::error_code ec;
  std::filesystem::create_directories(TilesDir(id), ec);
  absl::Status s = WriteTileFile(path, tile);
  if (s.ok() && !job->ended) s = store_->MarkTileDone(id, tile_index, NowMs());
  if (!s.ok()) return EndJob(id, pdsm::v1::FAILED, absl::StrCat("storing tile ", tile_index,
                                                                ": ", s.message()));
  spdlog::debug("job {} tile {}: assembled, {} events -> {} vertices", id, tile_index,
                stats.merged_events, stats.vertices);
  bool complete = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (job->ended) return;
    scheduler_.TileAssembled(id, tile_index);
    ++job->tiles_done;
    complete = scheduler_.JobComplete(id);
  }
  if (complete) FinishJob(job);
}

void Coordinator::FinishJob(std::shared_ptr<ActiveJob> job) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (job->ended) return;
  }
  const std::string& id = job->record.job_id;
  const std::string dir = JobDir(id);
  const std::string out = (std::filesystem::path(dir) / "pdsm.exr").string();
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  absl::Status s = [&]() -> absl::Status {
    absl::StatusOr<std::unique_ptr<PdsmWriter>> writer = PdsmWriter::Create(out, job->plan.header);
    if (!writer.ok()) return writer.status();
    for (const TileRect& rect : job->plan.tiles) {
      absl::StatusOr<PdsmTile> tile = ReadTileFile(TilePath(id, rect.index));
      if (!tile.ok()) return tile.status();
      if (absl::Status w = (*writer)->WriteTile(*tile); !w.ok()) return w;
    }
    return (*writer)->Finish();
  }();
  if (!s.ok()) return EndJob(id, pdsm::v1::FAILED, absl::StrCat("writing the PDSM: ", s.message()));
  {
    // A cancel that won the race keeps the job CANCELLED; the file goes.
    std::lock_guard<std::mutex> lock(mu_);
    if (job->ended) {
      std::filesystem::remove(out, ec);
      return;
    }
    job->ended = true;
    active_.erase(id);
    scheduler_.RemoveJob(id);
  }
  // A crash before this commit leaves the job RUNNING with every tile done: the next start
  // writes the file again from the same tiles.
  s = store_->SetSucceeded(id, std::filesystem::file_size(out, ec), NowMs());
  if (!s.ok()) {
    spdlog::error("job {}: cannot record SUCCEEDED: {}", id, std::string(s.message()));
    return;
  }
  std::filesystem::remove_all(TilesDir(id), ec);
  spdlog::info("job {}: succeeded, {} tiles, PDSM {}", id, job->plan.tiles.size(), out);
}

// ---- Queries ---------------------------------------------------------------------------

pdsm::v1::Job Coordinator::ToProto(const JobRecord& record) const {
  pdsm::v1::Job job;
  job.set_job_id(record.job_id);
  job.set_idempotency_key(record.idempotency_key);
  job.set_scene_name(record.scene_name);
  job.set_state(record.state);
  job.set_priority(record.priority);
  job.set_error(record.error);
  job.set_tiles_total(record.tiles_total);
  job.set_tiles_done(record.tiles_done);
  job.set_samples_total(record.samples_total);
  job.set_samples_done(record.state == pdsm::v1::SUCCEEDED
                           ? record.samples_total
                           : int64_t{record.tiles_done} * record.samples);
  job.set_created_unix_ms(record.created_unix_ms);
  job.set_updated_unix_ms(record.updated_unix_ms);
  job.set_pdsm_bytes(record.pdsm_bytes);
  job.set_tile_assemblies(record.tile_assemblies);
  job.set_width(record.width);
  job.set_height(record.height);
  job.set_samples(record.samples);
  job.set_eta_seconds(record.state == pdsm::v1::SUCCEEDED ? 0 : -1);
  return job;
}

absl::StatusOr<pdsm::v1::Job> Coordinator::GetJob(const std::string& job_id) {
  absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
  if (!record.ok()) return record.status();
  pdsm::v1::Job job = ToProto(*record);
  {
    std::lock_guard<std::mutex> lock(mu_);
    auto it = active_.find(job_id);
    if (it != active_.end() && !IsTerminal(record->state)) {
      const ActiveJob& a = *it->second;
      if (a.running) job.set_state(pdsm::v1::RUNNING);
      job.set_tiles_done(a.tiles_done);
      job.set_samples_done(a.samples_done);
      const double elapsed_s = (NowMs() - a.resumed_ms) / 1000.0;
      const int64_t gained = a.samples_done - a.samples_at_resume;
      if (gained > 0 && elapsed_s > 0) {
        job.set_eta_seconds((record->samples_total - a.samples_done) * elapsed_s / gained);
      }
    }
  }
  job.set_progress(job.samples_total() > 0
                       ? static_cast<double>(job.samples_done()) / job.samples_total()
                       : (job.state() == pdsm::v1::SUCCEEDED ? 1.0 : 0.0));
  return job;
}

absl::StatusOr<std::vector<pdsm::v1::Job>> Coordinator::ListJobs(int limit) {
  absl::StatusOr<std::vector<JobRecord>> records = store_->ListJobs(limit > 0 ? limit : 100);
  if (!records.ok()) return records.status();
  std::vector<pdsm::v1::Job> jobs;
  for (const JobRecord& r : *records) {
    absl::StatusOr<pdsm::v1::Job> job = GetJob(r.job_id);
    if (job.ok()) jobs.push_back(*std::move(job));
  }
  return jobs;
}

absl::StatusOr<std::string> Coordinator::PdsmPath(const std::string& job_id) {
  absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
  if (!record.ok()) return record.status();
  if (record->state != pdsm::v1::SUCCEEDED) {
    return absl::FailedPreconditionError(absl::StrCat(
        "job ", job_id, " is ", pdsm::v1::JobState_Name(record->state), ", not SUCCEEDED"));
  }
  return (std::filesystem::path(JobDir(job_id)) / "pdsm.exr").string();
}

absl::StatusOr<std::vector<int>> Coordinator::FinishedTiles(const std::string& job_id) {
  std::shared_ptr<ActiveJob> job;
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (auto it = active_.find(job_id); it != active_.end()) job = it->second;
  }
  if (!job || job->ended) {
    absl::StatusOr<JobRecord> record = store_->GetJob(job_id);
    if (!record.ok()) return record.status();
    return absl::FailedPreconditionError(absl::StrCat(
        "job ", job_id, " is ", pdsm::v1::JobState_Name(record->state),
        ": its tiles are only served while it runs"));
  }
  // A tile file exists once it is complete (written under a temporary name, then renamed).
  std::vector<int> done;
  std::error_code ec;
  for (const TileRect& rect : job->plan.tiles) {
    if (std::filesystem::exists(TilePath(job_id, rect.index), ec)) done.push_back(rect.index);
  }
  return done;
}

absl::StatusOr<std::string> Coordinator::FinishedTilePath(const std::string& job_id,
                                                          int tile_index) {
  absl::StatusOr<std::vector<int>> done = FinishedTiles(job_id);
  if (!done.ok()) return done.status();
  if (!std::binary_search(done->begin(), done->end(), tile_index)) {
    return absl::NotFoundError(
        absl::StrCat("job ", job_id, ": tile ", tile_index, " is not assembled (yet)"));
  }
  return TilePath(job_id, tile_index);
}

absl::StatusOr<std::vector<double>> Coordinator::Query(
    const std::string& job_id, const std::vector<glm::dvec3>& points_world) {
  absl::StatusOr<std::string> path = PdsmPath(job_id);
  if (!path.ok()) return path.status();
  std::shared_ptr<const PdsmImage> image;
  {
    std::lock_guard<std::mutex> lock(query_mu_);
    if (query_job_ == job_id) image = query_image_;
  }
  if (!image) {
    absl::StatusOr<PdsmImage> read = ReadPdsm(*path);
    if (!read.ok()) return read.status();
    image = std::make_shared<const PdsmImage>(*std::move(read));
    std::lock_guard<std::mutex> lock(query_mu_);
    query_job_ = job_id;
    query_image_ = image;
  }
  std::vector<double> out;
  out.reserve(points_world.size());
  for (const glm::dvec3& p : points_world) out.push_back(QueryAttenuation(*image, p));
  return out;
}

pdsm::v1::Stats Coordinator::GetStats() {
  pdsm::v1::Stats stats;
  std::lock_guard<std::mutex> lock(mu_);
  const int64_t now = NowMs();
  const SchedulerStats s = scheduler_.Stats(now);
  for (const auto& [id, job] : active_) {
    if (job->running) {
      stats.set_jobs_running(stats.jobs_running() + 1);
    } else {
      stats.set_jobs_queued(stats.jobs_queued() + 1);
    }
  }
  stats.set_tasks_pending(s.tasks_pending);
  stats.set_tasks_leased(s.tasks_leased);
  stats.set_tiles_in_flight(s.tiles_open);
  stats.set_workers_active(s.workers_active);
  int64_t events = 0, results = 0;
  for (const auto& [t, e] : recent_results_) {
    if (t >= now - kRateWindowMs) events += e, ++results;
  }
  const double window_s = std::min<double>(kRateWindowMs, std::max<int64_t>(1, now - started_ms_)) / 1000.0;
  stats.set_tasks_per_second(results / window_s);
  stats.set_events_per_second(events / window_s);
  stats.set_tasks_accepted(s.results_accepted);
  stats.set_results_dropped(s.results_dropped);
  stats.set_leases_expired(s.leases_expired);
  stats.set_uptime_seconds((now - started_ms_) / 1000.0);
  return stats;
}

// ---- Assets ----------------------------------------------------------------------------

std::vector<std::string> Coordinator::FindMissingAssets(
    const std::vector<std::string>& sha256) const {
  std::vector<std::string> missing;
  for (const std::string& h : sha256) {
    if (!assets_->Has(h)) missing.push_back(h);
  }
  return missing;
}

absl::Status Coordinator::PutAsset(const std::string& sha256, std::string_view bytes) {
  if (static_cast<int64_t>(bytes.size()) > options_.max_asset_bytes) {
    return absl::ResourceExhaustedError(absl::StrCat(
        "asset ", sha256, ": ", bytes.size(), " bytes, above the limit of ",
        options_.max_asset_bytes));
  }
  // Refuse blobs that are not meshes now, not when a job needs them.
  if (absl::Status s = DecodeMeshAsset(bytes, absl::StrCat("asset ", sha256)).status();
      !s.ok()) {
    return s;
  }
  return assets_->Put(sha256, bytes);
}

absl::StatusOr<std::string> Coordinator::GetAsset(const std::string& sha256) const {
  if (!IsSha256Hex(sha256)) {
    return absl::InvalidArgumentError("sha256: must be 64 lowercase hex characters");
  }
  return assets_->Get(sha256);
}

// ---- Worker API ------------------------------------------------------------------------

std::optional<pdsm::v1::Task> Coordinator::LeaseTask(const std::string& worker_id) {
  std::shared_ptr<ActiveJob> job;
  std::optional<TaskLease> lease;
  bool first_lease = false;
  {
    std::lock_guard<std::mutex> lock(mu_);
    lease = scheduler_.Lease(worker_id, NowMs());
    if (!lease) return std::nullopt;
    job = active_.at(lease->job_id);
    first_lease = !job->running;
    job->running = true;
  }
  if (first_lease) {
    if (absl::Status s = store_->SetState(lease->job_id, pdsm::v1::RUNNING, "", NowMs());
        !s.ok()) {
      spdlog::error("job {}: cannot record RUNNING: {}", lease->job_id, std::string(s.message()));
    }
  }
  spdlog::debug("job {} tile {}: samples [{}, {}) leased to {} (lease {})", lease->job_id,
                lease->tile_index, lease->sample_begin, lease->sample_end, worker_id,
                lease->lease_id);
  pdsm::v1::Task task;
  task.set_job_id(lease->job_id);
  task.set_lease_id(lease->lease_id);
  task.set_tile_index(lease->tile_index);
  task.set_sample_begin(lease->sample_begin);
  task.set_sample_end(lease->sample_end);
  task.set_lease_ms(options_.lease_ms);
  task.set_plan_fingerprint(job->fingerprint);
  return task;
}

absl::StatusOr<int64_t> Coordinator::ExtendLease(const std::string& worker_id,
                                                 uint64_t lease_id) {
  std::lock_guard<std::mutex> lock(mu_);
  absl::StatusOr<int64_t> deadline = scheduler_.Extend(worker_id, lease_id, NowMs());
  if (!deadline.ok()) return deadline.status();
  return options_.lease_ms;
}

absl::StatusOr<bool> Coordinator::ReportResult(const std::string& worker_id, uint64_t lease_id,
                                               const pdsm::v1::TileEventsData& data) {
  std::shared_ptr<ActiveJob> job;
  std::optional<TaskLease> lease;
  {
    std::lock_guard<std::mutex> lock(mu_);
    lease = scheduler_.FindLease(lease_id);
    if (lease) {
      auto it = active_.find(lease->job_id);
      if (it != active_.end()) job = it->second;
    }
  }
  if (!lease || !job) {
    std::lock_guard<std::mutex> lock(mu_);
    scheduler_.Complete(worker_id, lease_id, NowMs());  // counts the drop
    return false;
  }
  // Decode outside the lock: it is the one per-event pass of the coordinator's hot path.
  absl::StatusOr<TileEvents> events =
      TileEventsFromProto(data, job->plan.tiles.at(lease->tile_index));
  if (!events.ok()) return events.status();

  std::vector<std::pair<int, TileEvents>> parts;
  {
    std::lock_guard<std::mutex> lock(mu_);
    const int64_t now = NowMs();
    const ResultOutcome outcome = scheduler_.Complete(worker_id, lease_id, now);
    if (outcome.kind == ResultOutcome::kDropped || job->ended) {
      spdlog::debug("job {} tile {}: dropped a late or duplicate result from {}", lease->job_id,
                    lease->tile_index, worker_id);
      return false;
    }
    recent_results_.emplace_back(now, static_cast<int64_t>(events->events.size()));
    job->samples_done += outcome.sample_end - outcome.sample_begin;
    auto& tile_parts = job->parts[outcome.tile_index];
    tile_parts.emplace_back(outcome.sample_begin, *std::move(events));
    if (outcome.kind == ResultOutcome::kTileComplete) {
      parts.swap(tile_parts);
      job->parts.erase(outcome.tile_index);
    }
  }
  if (!parts.empty()) {
    const int tile = lease->tile_index;
    Post([this, job, tile, p = std::move(parts)]() mutable {
      if (job->plan.header.adaptive()) {
        JudgeStage(job, tile, std::move(p));
      } else {
        AssembleAndStore(job, tile, std::move(p), 0);
      }
    });
  }
  return true;
}

void Coordinator::ReportFailure(const std::string& worker_id, uint64_t lease_id,
                                const std::string& reason, bool handed_back) {
  std::optional<JobFailure> failure;
  {
    std::lock_guard<std::mutex> lock(mu_);
    failure = scheduler_.Fail(worker_id, lease_id, reason, handed_back, NowMs());
  }
  spdlog::warn("lease {}: worker {} {}: {}", lease_id, worker_id,
               handed_back ? "handed the task back" : "failed", reason);
  if (failure) EndJob(failure->job_id, pdsm::v1::FAILED, failure->reason);
}

absl::StatusOr<pdsm::v1::GetJobSceneResponse> Coordinator::JobScene(const std::string& job_id) {
  std::lock_guard<std::mutex> lock(mu_);
  auto it = active_.find(job_id);
  if (it == active_.end()) {
    return absl::FailedPreconditionError(absl::StrCat("job ", job_id, " is not running"));
  }
  pdsm::v1::GetJobSceneResponse response;
  *response.mutable_scene() = it->second->scene;
  response.set_plan_fingerprint(it->second->fingerprint);
  return response;
}

}  // namespace pdsm
