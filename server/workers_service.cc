#include "server/workers_service.h"

#include <cmath>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"
#include "rpc/grpc_support.h"
#include "server/call_replies.h"
#include "server/failure_codes.h"
#include "server/request_checks.h"

namespace pdsm {
namespace {

// Without work, a worker asks again after this long: short enough that a new job starts
// promptly, long enough that idle workers cost the coordinator little.
constexpr int64_t kIdleRetryMs = 250;

// ReportFailureRequest.code: an absl/gRPC code name; anything else (empty: an older worker)
// is UNKNOWN. A failure is never OK.
absl::StatusCode FailureCode(const std::string& name) {
  for (const absl::StatusCode c : kFailureCodes) {
    if (absl::StatusCodeToString(c) == name) return c;
  }
  return absl::StatusCode::kUnknown;
}

// FetchAsset: the blob in chunks.
class AssetReactor final : public grpc::ServerWriteReactor<pdsm::v1::AssetData> {
 public:
  explicit AssetReactor(absl::StatusOr<std::string> blob) {
    if (!blob.ok()) {
      Finish(ToGrpcStatus(blob.status()));
      return;
    }
    blob_ = *std::move(blob);
    chunk_.set_total_bytes(blob_.size());
    Next();
  }
  void OnWriteDone(bool ok) override {
    if (!ok) return Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "write failed"));
    chunk_.clear_total_bytes();
    Next();
  }
  void OnDone() override { delete this; }

 private:
  void Next() {
    if (offset_ == blob_.size() && sent_any_) return Finish(grpc::Status::OK);
    const size_t n = std::min(kChunkBytes, blob_.size() - offset_);
    chunk_.set_data(blob_.substr(offset_, n));
    offset_ += n;
    sent_any_ = true;
    StartWrite(&chunk_);
  }
  std::string blob_;
  size_t offset_ = 0;
  bool sent_any_ = false;
  pdsm::v1::AssetData chunk_;
};

}  // namespace

grpc::ServerUnaryReactor* WorkersService::LeaseTask(grpc::CallbackServerContext* context,
                                                    const pdsm::v1::LeaseTaskRequest* request,
                                                    pdsm::v1::LeaseTaskResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckWorkerId(request->worker_id()); !s.ok()) return Answer(context, s);
  if (coordinator_->Quarantined(request->worker_id())) {
    // Not retryable: the worker exits with this line instead of idling on its allocation.
    return Answer(context,
                  grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                               "this worker was quarantined: verification found its results "
                               "differ from two other workers' for the same task (the "
                               "coordinator's log says which); check the machine (memory, GPU "
                               "driver, build) before starting a worker on it again"));
  }
  std::optional<pdsm::v1::Task> task = coordinator_->LeaseTask(request->worker_id());
  if (task) {
    *response->mutable_task() = *std::move(task);
  } else {
    response->set_retry_after_ms(kIdleRetryMs);
  }
  return Answer(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* WorkersService::ExtendLease(grpc::CallbackServerContext* context,
                                                      const pdsm::v1::ExtendLeaseRequest* request,
                                                      pdsm::v1::ExtendLeaseResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckWorkerId(request->worker_id()); !s.ok()) return Answer(context, s);
  absl::StatusOr<int64_t> lease_ms =
      coordinator_->ExtendLease(request->worker_id(), request->lease_id());
  if (!lease_ms.ok()) return Answer(context, lease_ms.status());
  response->set_lease_ms(*lease_ms);
  return Answer(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* WorkersService::ReportResult(grpc::CallbackServerContext* context,
                                                       const pdsm::v1::ReportResultRequest* request,
                                                       pdsm::v1::ReportResultResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckWorkerId(request->worker_id()); !s.ok()) return Answer(context, s);
  if (!std::isfinite(request->seconds()) || request->seconds() < 0) {
    return Answer(
        context,
        ToGrpcStatus(absl::InvalidArgumentError("seconds: must be finite and not negative")));
  }
  absl::StatusOr<bool> accepted = coordinator_->ReportResult(
      request->worker_id(), request->lease_id(), request->tiles(), request->seconds());
  if (!accepted.ok()) return Answer(context, accepted.status());
  response->set_accepted(*accepted);
  return Answer(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* WorkersService::ReportFailure(
    grpc::CallbackServerContext* context, const pdsm::v1::ReportFailureRequest* request,
    pdsm::v1::ReportFailureResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckWorkerId(request->worker_id()); !s.ok()) return Answer(context, s);
  // Escaped here, once: the reason goes into logs and into the job's error, one line each.
  coordinator_->ReportFailure(
      request->worker_id(), request->lease_id(),
      absl::Status(FailureCode(request->code()), Printable(request->reason(), kMaxReasonBytes)),
      request->handed_back(), request->incompatible());
  return Answer(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* WorkersService::SignOff(grpc::CallbackServerContext* context,
                                                  const pdsm::v1::SignOffRequest* request,
                                                  pdsm::v1::SignOffResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckWorkerId(request->worker_id()); !s.ok()) return Answer(context, s);
  coordinator_->SignOff(request->worker_id());
  return Answer(context, grpc::Status::OK);
}

grpc::ServerUnaryReactor* WorkersService::GetJobScene(grpc::CallbackServerContext* context,
                                                      const pdsm::v1::GetJobSceneRequest* request,
                                                      pdsm::v1::GetJobSceneResponse* response) {
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) {
    return Answer(context, s);
  }
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) return Answer(context, s);
  absl::StatusOr<pdsm::v1::GetJobSceneResponse> scene = coordinator_->JobScene(request->job_id());
  if (!scene.ok()) return Answer(context, scene.status());
  *response = *std::move(scene);
  return Answer(context, grpc::Status::OK);
}

grpc::ServerWriteReactor<pdsm::v1::AssetData>* WorkersService::FetchAsset(
    grpc::CallbackServerContext* context, const pdsm::v1::FetchAssetRequest* request) {
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) {
    return new RefusedStream<grpc::ServerWriteReactor<pdsm::v1::AssetData>>(s);
  }
  return new AssetReactor(coordinator_->assets().Get(request->sha256()));
}

grpc::ServerWriteReactor<pdsm::v1::AssetData>* WorkersService::FetchRefinement(
    grpc::CallbackServerContext* context, const pdsm::v1::FetchRefinementRequest* request) {
  using Refused = RefusedStream<grpc::ServerWriteReactor<pdsm::v1::AssetData>>;
  if (grpc::Status s = auth_->Check(context, Audience::kWorker); !s.ok()) return new Refused(s);
  if (absl::Status s = CheckJobId(request->job_id()); !s.ok()) {
    return new Refused(ToGrpcStatus(s));
  }
  if (absl::Status s = CheckLightName(request->light()); !s.ok()) {
    return new Refused(ToGrpcStatus(s));
  }
  absl::StatusOr<std::shared_ptr<const std::string>> blob =
      coordinator_->RefinedPixelsBlob(request->job_id(), request->light());
  if (!blob.ok()) return new AssetReactor(blob.status());
  return new AssetReactor(**blob);
}

}  // namespace pdsm
