#include "server/jobs_service.h"

#include <algorithm>
#include <fstream>
#include <sstream>

#include <spdlog/spdlog.h>

#include "absl/strings/str_cat.h"
#include "core/assets/mesh_asset.h"
#include "rpc/grpc_support.h"
#include "server/call_replies.h"
#include "server/request_checks.h"
#include "server/watch_hub.h"

namespace pdsm {
namespace {

constexpr int kMaxAssetQueries = 10'000;
constexpr int kMaxQueryPoints = 1'000'000;

// UploadAsset: collects the chunks, verifies size and hash, stores the blob.
class UploadReactor final : public grpc::ServerReadReactor<pdsm::v1::AssetChunk> {
 public:
  UploadReactor(Coordinator* coordinator, pdsm::v1::UploadAssetResponse* response)
      : coordinator_(coordinator), response_(response) {
    StartRead(&chunk_);
  }

  void OnReadDone(bool ok) override {
    if (!ok) return Complete();
    if (first_) {
      first_ = false;
      sha256_ = chunk_.sha256();
      if (!IsSha256Hex(sha256_)) {
        return Fail(absl::InvalidArgumentError(
            "sha256: the first chunk must name the blob's 64-hex-digit SHA-256"));
      }
      if (static_cast<int64_t>(chunk_.total_bytes()) > coordinator_->assets().max_asset_bytes()) {
        return Fail(absl::ResourceExhaustedError(
            absl::StrCat("total_bytes: ", chunk_.total_bytes(), " is above the asset limit of ",
                         coordinator_->assets().max_asset_bytes())));
      }
      expected_bytes_ = chunk_.total_bytes();
      // Grow with the data, not with the claim: a client may announce more than it sends.
      blob_.reserve(std::min<uint64_t>(expected_bytes_, kChunkBytes));
    }
    ++chunks_;
    if (chunk_.data().size() > kChunkBytes) {
      return Fail(absl::InvalidArgumentError(
          absl::StrCat("data: chunk ", chunks_ - 1, " holds ", chunk_.data().size(),
                       " bytes, a chunk holds at most ", kChunkBytes)));
    }
    if (!chunk_.sha256().empty() && chunk_.sha256() != sha256_) {
      return Fail(absl::InvalidArgumentError(
          absl::StrCat("sha256: chunk ", chunks_ - 1, " names another blob than the first chunk")));
    }
    if (blob_.size() + chunk_.data().size() > expected_bytes_) {
      return Fail(absl::InvalidArgumentError(
          absl::StrCat("data: more bytes than the announced total_bytes (", expected_bytes_, ")")));
    }
    blob_ += chunk_.data();
    StartRead(&chunk_);
  }

  void OnDone() override { delete this; }

 private:
  void Complete() {
    if (first_) return Fail(absl::InvalidArgumentError("no chunk received"));
    if (blob_.size() != expected_bytes_) {
      return Fail(absl::InvalidArgumentError(absl::StrCat(
          "data: got ", blob_.size(), " bytes, total_bytes announced ", expected_bytes_)));
    }
    if (absl::Status s = coordinator_->assets().Put(sha256_, blob_); !s.ok()) return Fail(s);
    response_->set_sha256(sha256_);
    response_->set_bytes(blob_.size());
    spdlog::info("asset {}: stored, {} bytes", sha256_, blob_.size());
    Finish(grpc::Status::OK);
  }

  void Fail(const absl::Status& status) { Finish(ToGrpcStatus(status)); }

  Coordinator* coordinator_;
  pdsm::v1::UploadAssetResponse* response_;
  pdsm::v1::AssetChunk chunk_;
  bool first_ = true;
  int64_t chunks_ = 0;  // received so far
  std::string sha256_;
  uint64_t expected_bytes_ = 0;
  std::string blob_;
};

// FetchPdsm: streams the file in chunks, one write in flight at a time.
class FetchReactor final : public grpc::ServerWriteReactor<pdsm::v1::PdsmChunk> {
 public:
  // Streams the file at `path` (a PDSM).
  explicit FetchReactor(const absl::StatusOr<std::string>& path) {
    if (!path.ok()) {
      Finish(ToGrpcStatus(path.status()));
      return;
    }
    file_.open(*path, std::ios::binary);
    if (!file_) {
      Finish(grpc::Status(grpc::StatusCode::DATA_LOSS, "the PDSM file cannot be read"));
      return;
    }
    in_ = &file_;
    Start();
  }
  // Streams `bytes` (a tile file).
  struct Bytes {
    absl::StatusOr<std::string> bytes;
  };
  explicit FetchReactor(Bytes bytes) {
    if (!bytes.bytes.ok()) {
      Finish(ToGrpcStatus(bytes.bytes.status()));
      return;
    }
    memory_.str(*std::move(bytes.bytes));
    in_ = &memory_;
    Start();
  }

  void OnWriteDone(bool ok) override {
    if (!ok) return Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "write failed"));
    chunk_.clear_total_bytes();
    Next();
  }

  void OnDone() override { delete this; }

 private:
  void Start() {
    in_->seekg(0, std::ios::end);
    total_ = static_cast<uint64_t>(in_->tellg());
    in_->seekg(0);
    chunk_.set_total_bytes(total_);
    Next();
  }

  void Next() {
    if (sent_ == total_ && sent_any_) return Finish(grpc::Status::OK);
    std::string data(std::min<uint64_t>(kChunkBytes, total_ - sent_), '\0');
    in_->read(data.data(), static_cast<std::streamsize>(data.size()));
    if (!*in_) return Finish(grpc::Status(grpc::StatusCode::DATA_LOSS, "short read"));
    sent_ += data.size();
    sent_any_ = true;
    *chunk_.mutable_data() = std::move(data);
    StartWrite(&chunk_);
  }

  std::ifstream file_;
  std::istringstream memory_;
  std::istream* in_ = nullptr;  // file_ or memory_
  uint64_t total_ = 0, sent_ = 0;
  bool sent_any_ = false;
  pdsm::v1::PdsmChunk chunk_;
};

}  // namespace

JobsService::JobsService(Coordinator* coordinator, const CallerAuth* auth)
    : coordinator_(coordinator), auth_(auth), watch_hub_(std::make_unique<WatchHub>(coordinator)) {}

JobsService::~JobsService() = default;

void JobsService::Shutdown() { watch_hub_->Shutdown(); }

grpc::ServerUnaryReactor* JobsService::FindMissingAssets(
    grpc::CallbackServerContext* context, const pdsm::v1::FindMissingAssetsRequest* request,
    pdsm::v1::FindMissingAssetsResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return Answer(context, s);
  }
  if (request->sha256_size() > kMaxAssetQueries) {
    return Answer(context, absl::ResourceExhaustedError(
                               absl::StrCat("sha256: at most ", kMaxAssetQueries, " per call")));
  }
  std::vector<std::string> hashes;
  for (int i = 0; i < request->sha256_size(); ++i) {
    if (!IsSha256Hex(request->sha256(i))) {
      return Answer(context, absl::InvalidArgumentError(absl::StrCat(
                                 "sha256[", i, "]: must be 64 lowercase hex characters")));
    }
    hashes.push_back(request->sha256(i));
  }
  for (std::string& h : coordinator_->assets().FindMissing(hashes)) {
    response->add_missing_sha256(std::move(h));
  }
  return Answer(context, grpc::Status::OK);
}

grpc::ServerReadReactor<pdsm::v1::AssetChunk>* JobsService::UploadAsset(
    grpc::CallbackServerContext* context, pdsm::v1::UploadAssetResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return new RefusedStream<grpc::ServerReadReactor<pdsm::v1::AssetChunk>>(s);
  }
  return new UploadReactor(coordinator_, response);
}

grpc::ServerUnaryReactor* JobsService::SubmitBake(grpc::CallbackServerContext* context,
                                                  const pdsm::v1::SubmitBakeRequest* request,
                                                  pdsm::v1::Job* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return Answer(context, s);
  }
  // Planned on the coordinator's admission thread: a gRPC thread only hands it over.
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  coordinator_->SubmitBakeAsync(request, [reactor, response, peer = context->peer()](
                                             absl::StatusOr<pdsm::v1::Job> job) {
    if (!job.ok()) {
      spdlog::warn("SubmitBake refused ({}): {}", peer, Printable(job.status().message(), 1024));
      reactor->Finish(ToGrpcStatus(job.status()));
      return;
    }
    *response = *std::move(job);
    reactor->Finish(grpc::Status::OK);
  });
  return reactor;
}

grpc::ServerUnaryReactor* JobsService::GetJob(grpc::CallbackServerContext* context,
                                              const pdsm::v1::GetJobRequest* request,
                                              pdsm::v1::Job* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kMonitor); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) return Answer(context, s);
  absl::StatusOr<pdsm::v1::Job> job = coordinator_->GetJob(request->job_id());
  if (!job.ok()) return Answer(context, job.status());
  *response = *std::move(job);
  return Answer(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* JobsService::ListJobs(grpc::CallbackServerContext* context,
                                                const pdsm::v1::ListJobsRequest* request,
                                                pdsm::v1::ListJobsResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kMonitor); !s.ok()) {
    return Answer(context, s);
  }
  if (request->limit() < 0 || request->limit() > 10'000) {
    return Answer(context, absl::InvalidArgumentError("limit: must be in [0, 10000]"));
  }
  absl::StatusOr<std::vector<pdsm::v1::Job>> jobs = coordinator_->ListJobs(request->limit());
  if (!jobs.ok()) return Answer(context, jobs.status());
  for (pdsm::v1::Job& job : *jobs) *response->add_jobs() = std::move(job);
  return Answer(context, grpc::Status::OK);
}

grpc::ServerWriteReactor<pdsm::v1::Job>* JobsService::WatchJob(
    grpc::CallbackServerContext* context, const pdsm::v1::GetJobRequest* request) {
  if (grpc::Status s = auth_->Check(context, Audience::kMonitor); !s.ok()) {
    return new RefusedStream<grpc::ServerWriteReactor<pdsm::v1::Job>>(s);
  }
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) {
    return new RefusedStream<grpc::ServerWriteReactor<pdsm::v1::Job>>(ToGrpcStatus(s));
  }
  return watch_hub_->Watch(request->job_id());
}

grpc::ServerUnaryReactor* JobsService::CancelJob(grpc::CallbackServerContext* context,
                                                 const pdsm::v1::GetJobRequest* request,
                                                 pdsm::v1::Job* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) return Answer(context, s);
  absl::StatusOr<pdsm::v1::Job> job = coordinator_->CancelJob(request->job_id());
  if (!job.ok()) return Answer(context, job.status());
  *response = *std::move(job);
  return Answer(context, grpc::Status::OK);
}

grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>* JobsService::FetchPdsm(
    grpc::CallbackServerContext* context, const pdsm::v1::GetJobRequest* request) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return new RefusedStream<grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>>(s);
  }
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) {
    return new RefusedStream<grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>>(ToGrpcStatus(s));
  }
  return new FetchReactor(coordinator_->PdsmPath(request->job_id()));
}

grpc::ServerUnaryReactor* JobsService::ListFinishedTiles(
    grpc::CallbackServerContext* context, const pdsm::v1::ListFinishedTilesRequest* request,
    pdsm::v1::FinishedTiles* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) return Answer(context, s);
  if (absl::Status s = CheckLightName(request->light()); !s.ok()) return Answer(context, s);
  absl::StatusOr<std::vector<int>> tiles =
      coordinator_->FinishedTiles(request->job_id(), request->light());
  if (!tiles.ok()) return Answer(context, tiles.status());
  response->mutable_tile_indices()->Assign(tiles->begin(), tiles->end());
  return Answer(context, grpc::Status::OK);
}

grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>* JobsService::FetchTile(
    grpc::CallbackServerContext* context, const pdsm::v1::FetchTileRequest* request) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return new RefusedStream<grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>>(s);
  }
  absl::Status valid = CheckJobId(request->job_id());
  if (valid.ok()) valid = CheckLightName(request->light());
  if (valid.ok() && request->tile_index() < 0) {
    valid = absl::InvalidArgumentError(
        absl::StrCat("tile_index: must be >= 0 (got ", request->tile_index(), ")"));
  }
  if (!valid.ok()) {
    return new RefusedStream<grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>>(ToGrpcStatus(valid));
  }
  return new FetchReactor(FetchReactor::Bytes{
      coordinator_->FinishedTileBytes(request->job_id(), request->light(), request->tile_index())});
}

grpc::ServerUnaryReactor* JobsService::QueryAttenuation(
    grpc::CallbackServerContext* context, const pdsm::v1::QueryAttenuationRequest* request,
    pdsm::v1::QueryAttenuationResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kClient); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) return Answer(context, s);
  if (absl::Status s = CheckLightName(request->light()); !s.ok()) return Answer(context, s);
  if (request->points_size() > kMaxQueryPoints) {
    return Answer(context, absl::ResourceExhaustedError(
                               absl::StrCat("points: at most ", kMaxQueryPoints, " per call")));
  }
  std::vector<glm::dvec3> points;
  points.reserve(request->points_size());
  for (int i = 0; i < request->points_size(); ++i) {
    const pdsm::v1::QueryPoint& p = request->points(i);
    if (!std::isfinite(p.x()) || !std::isfinite(p.y()) || !std::isfinite(p.z())) {
      return Answer(context,
                    absl::InvalidArgumentError(absl::StrCat("points[", i, "]: must be finite")));
    }
    points.emplace_back(p.x(), p.y(), p.z());
  }
  absl::StatusOr<QueryAnswer> answer =
      coordinator_->Query(request->job_id(), request->light(), points);
  if (!answer.ok()) return Answer(context, answer.status());
  response->mutable_attenuation()->Assign(answer->attenuation.begin(), answer->attenuation.end());
  response->mutable_lights()->Assign(answer->lights.begin(), answer->lights.end());
  return Answer(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* JobsService::GetStats(grpc::CallbackServerContext* context,
                                                const pdsm::v1::GetStatsRequest* request,
                                                pdsm::v1::Stats* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kMonitor); !s.ok()) {
    return Answer(context, s);
  }
  *response = coordinator_->GetStats();
  return Answer(context, grpc::Status::OK);
}

}  // namespace pdsm
