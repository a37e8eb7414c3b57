#include "worker/coordinator_client.h"

#include "absl/strings/str_cat.h"
#include "rpc/tile_events_codec.h"

namespace pdsm {
namespace {

using std::chrono::milliseconds;
constexpr milliseconds kShortCall(10'000);
constexpr milliseconds kLongCall(300'000);  // results and assets may be tens of MiB

}  // namespace

CoordinatorClient::CoordinatorClient(std::shared_ptr<grpc::Channel> channel, std::string token,
                                     std::string worker_id)
    : stub_(pdsm::v1::PdsmWorkers::NewStub(channel)),
      token_(std::move(token)),
      worker_id_(std::move(worker_id)) {}

absl::StatusOr<pdsm::v1::LeaseTaskResponse> CoordinatorClient::Lease() {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kShortCall);
  pdsm::v1::LeaseTaskRequest request;
  request.set_worker_id(worker_id_);
  pdsm::v1::LeaseTaskResponse response;
  if (absl::Status s = FromGrpcStatus(stub_->LeaseTask(&context, request, &response)); !s.ok()) {
    return s;
  }
  return response;
}

absl::StatusOr<int64_t> CoordinatorClient::Extend(uint64_t lease_id) {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kShortCall);
  pdsm::v1::ExtendLeaseRequest request;
  request.set_worker_id(worker_id_);
  request.set_lease_id(lease_id);
  pdsm::v1::ExtendLeaseResponse response;
  if (absl::Status s = FromGrpcStatus(stub_->ExtendLease(&context, request, &response)); !s.ok()) {
    return s;
  }
  return response.lease_ms();
}

absl::StatusOr<bool> CoordinatorClient::ReportResult(uint64_t lease_id,
                                                     const std::vector<TileEvents>& events,
                                                     double seconds) {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kLongCall);
  pdsm::v1::ReportResultRequest request;
  request.set_worker_id(worker_id_);
  request.set_lease_id(lease_id);
  request.set_seconds(seconds);
  for (const TileEvents& tile : events) TileEventsToProto(tile, request.add_tiles());
  pdsm::v1::ReportResultResponse response;
  if (absl::Status s = FromGrpcStatus(stub_->ReportResult(&context, request, &response)); !s.ok()) {
    return s;
  }
  return response.accepted();
}

absl::Status CoordinatorClient::ReportFailure(uint64_t lease_id, const absl::Status& failure,
                                              TaskFailure kind) {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kShortCall);
  pdsm::v1::ReportFailureRequest request;
  request.set_worker_id(worker_id_);
  request.set_lease_id(lease_id);
  request.set_reason(std::string(failure.message()));
  request.set_code(absl::StatusCodeToString(failure.code()));
  request.set_handed_back(kind == TaskFailure::kHandedBack);
  request.set_incompatible(kind == TaskFailure::kIncompatible);
  pdsm::v1::ReportFailureResponse response;
  return FromGrpcStatus(stub_->ReportFailure(&context, request, &response));
}

absl::Status CoordinatorClient::SignOff() {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kShortCall);
  pdsm::v1::SignOffRequest request;
  request.set_worker_id(worker_id_);
  pdsm::v1::SignOffResponse response;
  return FromGrpcStatus(stub_->SignOff(&context, request, &response));
}

absl::StatusOr<pdsm::v1::GetJobSceneResponse> CoordinatorClient::JobScene(
    const std::string& job_id) {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kLongCall);
  pdsm::v1::GetJobSceneRequest request;
  request.set_job_id(job_id);
  pdsm::v1::GetJobSceneResponse response;
  if (absl::Status s = FromGrpcStatus(stub_->GetJobScene(&context, request, &response)); !s.ok()) {
    return s;
  }
  return response;
}

namespace {

// A blob sent in chunks (FetchAsset, FetchRefinement), put together.
absl::StatusOr<std::string> ReadChunks(grpc::ClientReader<pdsm::v1::AssetData>* reader) {
  std::string blob;
  pdsm::v1::AssetData chunk;
  while (reader->Read(&chunk)) {
    if (chunk.total_bytes() > 0 && blob.empty()) blob.reserve(chunk.total_bytes());
    blob += chunk.data();
  }
  if (absl::Status s = FromGrpcStatus(reader->Finish()); !s.ok()) return s;
  return blob;
}

}  // namespace

absl::StatusOr<std::string> CoordinatorClient::FetchRefinement(const std::string& job_id,
                                                               const std::string& light) {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kLongCall);
  pdsm::v1::FetchRefinementRequest request;
  request.set_job_id(job_id);
  request.set_light(light);
  std::unique_ptr<grpc::ClientReader<pdsm::v1::AssetData>> reader =
      stub_->FetchRefinement(&context, request);
  return ReadChunks(reader.get());
}

absl::StatusOr<std::string> CoordinatorClient::FetchAsset(const std::string& sha256) {
  grpc::ClientContext context;
  PrepareCall(&context, token_, kLongCall);
  pdsm::v1::FetchAssetRequest request;
  request.set_sha256(sha256);
  std::unique_ptr<grpc::ClientReader<pdsm::v1::AssetData>> reader =
      stub_->FetchAsset(&context, request);
  return ReadChunks(reader.get());
}

}  // namespace pdsm
