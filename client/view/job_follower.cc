#include "client/view/job_follower.h"

#include <chrono>
#include <filesystem>

#include <unistd.h>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_join.h"
#include "client/view/pdsm_source.h"
#include "core/bake/plan_fingerprint.h"
#include "core/pipeline/tile_file.h"
#include "core/scene/scene_loader.h"
#include "spdlog/spdlog.h"

namespace pdsm::view {

absl::StatusOr<pdsm::v1::Job> FetchJob(const ServiceFlags& service, const std::string& job_id) {
  absl::StatusOr<ServiceConnection> c = Connect(service);
  if (!c.ok()) return c.status();
  pdsm::v1::GetJobRequest request;
  request.set_job_id(job_id);
  pdsm::v1::Job job;
  auto context = c->Call();
  if (grpc::Status s = c->stub->GetJob(context.get(), request, &job); !s.ok()) {
    return CallError("job " + job_id, s, service.server);
  }
  return job;
}

absl::StatusOr<const pdsm::v1::LightProgress*> FindJobLight(const pdsm::v1::Job& job,
                                                            const std::string& light) {
  if (job.lights_size() == 0 && light.empty()) return nullptr;
  if (light.empty() && job.lights_size() == 1) return &job.lights(0);
  std::vector<std::string> names;
  for (const pdsm::v1::LightProgress& l : job.lights()) {
    if (!light.empty() && l.name() == light) return &l;
    names.push_back(l.name());
  }
  const std::string listed = absl::StrCat("\"", absl::StrJoin(names, "\", \""), "\"");
  if (light.empty()) {
    return absl::InvalidArgumentError(absl::StrCat("--job ", job.job_id(), " bakes ",
                                                   job.lights_size(), " lights (", listed,
                                                   "): choose one with --light NAME"));
  }
  return absl::InvalidArgumentError(absl::StrCat("--job ", job.job_id(), " has no light \"", light,
                                                 "\" (its lights: ", listed, ")"));
}

absl::StatusOr<Scene> LoadJobScene(const std::string& scene_path, const pdsm::v1::Job& job,
                                   const std::string& light) {
  absl::StatusOr<const pdsm::v1::LightProgress*> found = FindJobLight(job, light);
  if (!found.ok()) return found.status();
  // Several lights: the light's own settings, laid over every light of the file (overrides
  // replace lights' own fields); the caller keeps that light only.
  if (job.lights_size() > 1 && (*found)->has_bake()) {
    return LoadSceneFile(scene_path, (*found)->bake());
  }
  if (!job.has_bake()) {
    spdlog::warn(
        "job {}: the coordinator does not report its bake settings (an older build): planning "
        "with {}'s own, which fails if the submit overrode any",
        job.job_id(), scene_path);
    return LoadSceneFile(scene_path);
  }
  return LoadSceneFile(scene_path, job.bake());
}

absl::Status CheckPlanMatchesJob(const BakePlan& plan, const pdsm::v1::Job& job,
                                 const std::string& light, const std::string& scene_path) {
  absl::StatusOr<const pdsm::v1::LightProgress*> found = FindJobLight(job, light);
  if (!found.ok()) return found.status();
  const std::string& theirs =
      *found != nullptr ? (*found)->plan_fingerprint() : job.plan_fingerprint();
  if (theirs.empty()) return absl::OkStatus();
  const std::string ours = PlanFingerprint(plan);
  if (ours == theirs) return absl::OkStatus();
  return absl::InvalidArgumentError(absl::StrCat(
      "--job ", job.job_id(), ": ", scene_path,
      " with the job's bake settings plans another PDSM than the job's (plan fingerprint ",
      ours.substr(0, 12), " vs ", theirs.substr(0, 12),
      "): give the scene file the job was submitted from, as it was then"));
}

PartialPdsm EmptyPartialPdsm(const BakePlan& plan) { return AssemblePartialPdsm(plan, {}); }

PartialPdsm AssemblePartialPdsm(const BakePlan& plan, const std::map<int, PdsmTile>& tiles) {
  PartialPdsm out;
  out.image.header = plan.header;
  const int width = plan.header.geometry.width, height = plan.header.geometry.height;
  const size_t pixels = static_cast<size_t>(width) * height;
  std::vector<const PdsmTile*> tile_of(pixels, nullptr);
  for (const TileRect& rect : AllTiles(plan)) {
    auto it = tiles.find(rect.index);
    if (it == tiles.end()) continue;
    for (int y = rect.y0; y < rect.y0 + rect.height; ++y) {
      for (int x = rect.x0; x < rect.x0 + rect.width; ++x) {
        tile_of[static_cast<size_t>(y) * width + x] = &it->second;
      }
    }
  }
  out.image.offsets.assign(pixels + 1, 0);
  bool any_pending = false;
  for (size_t p = 0; p < pixels; ++p) {
    const PdsmTile* tile = tile_of[p];
    if (tile != nullptr) {
      const int x = static_cast<int>(p % width) - tile->x0,
                y = static_cast<int>(p / width) - tile->y0;
      const std::span<const Vertex> f = tile->Function(x, y);
      out.image.vertices.insert(out.image.vertices.end(), f.begin(), f.end());
    }
    any_pending = any_pending || tile == nullptr;
    out.image.offsets[p + 1] = out.image.vertices.size();
  }
  if (any_pending) {
    out.pending.resize(pixels);
    for (size_t p = 0; p < pixels; ++p) out.pending[p] = tile_of[p] == nullptr;
  }
  return out;
}

absl::StatusOr<std::unique_ptr<JobFollower>> JobFollower::Create(const ServiceFlags& service,
                                                                 const std::string& job_id,
                                                                 const std::string& light,
                                                                 const BakePlan* plan) {
  absl::StatusOr<ServiceConnection> c = Connect(service);
  if (!c.ok()) return c.status();
  return std::unique_ptr<JobFollower>(new JobFollower(service, job_id, light, plan, *std::move(c)));
}

absl::StatusOr<std::string> JobFollower::FetchTileBytes(int tile_index) {
  auto context = connection_.Call(std::chrono::minutes(10));
  pdsm::v1::FetchTileRequest request;
  request.set_job_id(job_id_);
  request.set_light(light_);
  request.set_tile_index(tile_index);
  std::unique_ptr<grpc::ClientReader<pdsm::v1::PdsmChunk>> reader =
      connection_.stub->FetchTile(context.get(), request);
  std::string bytes;
  uint64_t total = 0;
  pdsm::v1::PdsmChunk chunk;
  for (bool first = true; reader->Read(&chunk); first = false) {
    if (first) total = chunk.total_bytes();
    bytes += chunk.data();
  }
  const std::string what = absl::StrCat("fetching tile ", tile_index, " of job ", job_id_);
  if (grpc::Status s = reader->Finish(); !s.ok()) return CallError(what, s, service_.server);
  if (bytes.size() != total) {
    return absl::DataLossError(absl::StrCat(what, ": got ", bytes.size(), " of ", total, " bytes"));
  }
  return bytes;
}

absl::StatusOr<JobSnapshot> JobFollower::Poll() {
  JobSnapshot snapshot;
  pdsm::v1::GetJobRequest request;
  request.set_job_id(job_id_);
  auto context = connection_.Call();
  if (grpc::Status s = connection_.stub->GetJob(context.get(), request, &snapshot.job); !s.ok()) {
    return CallError("job " + job_id_, s, service_.server);
  }
  const pdsm::v1::Job& job = snapshot.job;
  absl::StatusOr<const pdsm::v1::LightProgress*> light = FindJobLight(job, light_);
  if (!light.ok()) return light.status();
  const int width = *light ? (*light)->width() : job.width();
  const int height = *light ? (*light)->height() : job.height();
  const int samples = *light ? (*light)->samples() : job.samples();
  const PdsmGeometry& g = plan_->header.geometry;
  if (width != g.width || height != g.height || samples != plan_->header.samples) {
    return absl::InvalidArgumentError(absl::StrCat(
        "--job ", job_id_, ": the job bakes ", width, "x", height, " x ", samples,
        " samples, the scene file plans ", g.width, "x", g.height, " x ", plan_->header.samples,
        " with the job's settings (give the scene file the job was submitted from)"));
  }
  if (finished_) return snapshot;
  if (job.state() == pdsm::v1::FAILED || job.state() == pdsm::v1::CANCELLED) {
    return absl::FailedPreconditionError(
        absl::StrCat("--job ", job_id_, ": ", pdsm::v1::JobState_Name(job.state()),
                     job.error().empty() ? "" : ": ", job.error()));
  }
  if (job.state() == pdsm::v1::SUCCEEDED) {
    // ReadPdsm reads files: a temporary one, removed at once.
    const std::string temp = (std::filesystem::temp_directory_path() /
                              absl::StrCat("pdsm-view-", job_id_, "-", ::getpid(), ".exr"))
                                 .string();
    absl::StatusOr<uint64_t> received = DownloadPdsm(connection_, service_, job_id_, temp);
    absl::StatusOr<PdsmImage> image =
        received.ok() ? LoadPdsmFile(temp, light_) : absl::StatusOr<PdsmImage>(received.status());
    std::error_code ec;
    std::filesystem::remove(temp, ec);
    if (!image.ok()) return image.status();
    snapshot.pdsm = PartialPdsm{*std::move(image), {}};
    finished_ = true;
    return snapshot;
  }
  pdsm::v1::FinishedTiles finished;
  pdsm::v1::ListFinishedTilesRequest list;
  list.set_job_id(job_id_);
  list.set_light(light_);
  auto list_context = connection_.Call();
  grpc::Status s = connection_.stub->ListFinishedTiles(list_context.get(), list, &finished);
  // The job may end between the two calls; the next poll fetches the file.
  if (s.error_code() == grpc::StatusCode::FAILED_PRECONDITION) return snapshot;
  if (!s.ok()) return CallError("listing the tiles of job " + job_id_, s, service_.server);
  bool gained = false;
  for (int index : finished.tile_indices()) {
    if (tiles_.count(index) != 0) continue;
    absl::StatusOr<std::string> bytes = FetchTileBytes(index);
    if (!bytes.ok()) break;  // e.g. the job ended meanwhile: the next poll sorts it out
    absl::StatusOr<PdsmTile> tile =
        DecodeTileFile(*bytes, absl::StrCat("job ", job_id_, " tile ", index));
    if (!tile.ok()) return tile.status();
    tiles_.emplace(index, *std::move(tile));
    gained = true;
  }
  if (gained) snapshot.pdsm = AssemblePartialPdsm(*plan_, tiles_);
  return snapshot;
}

void JobFollower::Start(int interval_ms) {
  thread_ = std::thread([this, interval_ms] {
    while (!stop_) {
      absl::StatusOr<JobSnapshot> snapshot = Poll();
      {
        absl::MutexLock lock(&mu_);
        if (!snapshot.ok()) {
          error_ = snapshot.status();
          return;
        }
        if (!latest_ || snapshot->pdsm) {
          latest_ = *std::move(snapshot);
        } else {
          latest_->job = snapshot->job;  // keep the unread PDSM, update the state
        }
        if (finished_) return;  // the final PDSM is in latest_ or was taken
      }
      for (int waited = 0; waited < interval_ms && !stop_; waited += 20) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
      }
    }
  });
}

std::optional<JobSnapshot> JobFollower::Take() {
  absl::MutexLock lock(&mu_);
  std::optional<JobSnapshot> out = std::move(latest_);
  latest_.reset();
  return out;
}

absl::Status JobFollower::error() {
  absl::MutexLock lock(&mu_);
  return error_;
}

JobFollower::~JobFollower() {
  stop_ = true;
  if (thread_.joinable()) thread_.join();
}

}  // namespace pdsm::view
