// The worker's side of the worker API: one stub, every call with the worker token and a
// deadline. Statuses come back as absl::Status (UNAVAILABLE when the coordinator is away).
//
// Thread-safe: the worker's task threads and its lease keeper share one client. Every call
// makes its own grpc::ClientContext, and the stub and channel are safe for concurrent calls;
// the members are set once by the constructor.
#ifndef PDSM_WORKER_COORDINATOR_CLIENT_H_
#define PDSM_WORKER_COORDINATOR_CLIENT_H_

#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "absl/status/statusor.h"
#include "core/events/event.h"
#include "pdsm/v1/workers.grpc.pb.h"
#include "rpc/grpc_support.h"

namespace pdsm {

// Why a worker gives a task back (ReportFailureRequest): only kFailed counts against the task
// and the worker.
enum class TaskFailure {
  kFailed,        // it could not be done here
  kHandedBack,    // the worker is stopping; the task is undone, not failed
  kIncompatible,  // this build plans the job differently (plan fingerprint)
};

class CoordinatorClient {
 public:
  CoordinatorClient(std::shared_ptr<grpc::Channel> channel, std::string token,
                    std::string worker_id);

  const std::string& worker_id() const { return worker_id_; }

  absl::StatusOr<pdsm::v1::LeaseTaskResponse> Lease();
  // The lease's new length in ms; FAILED_PRECONDITION when the lease is lost.
  absl::StatusOr<int64_t> Extend(uint64_t lease_id);
  // True when the coordinator accepted the result, false when it dropped it as stale.
  // `events`: one per tile of the task, in its order.
  absl::StatusOr<bool> ReportResult(uint64_t lease_id, const std::vector<TileEvents>& events,
                                    double seconds);
  // `failure`: its message is the reason, its code is reported for the coordinator's counts.
  absl::Status ReportFailure(uint64_t lease_id, const absl::Status& failure, TaskFailure kind);
  // The worker is leaving (after handing back its tasks).
  absl::Status SignOff();
  absl::StatusOr<pdsm::v1::GetJobSceneResponse> JobScene(const std::string& job_id);
  absl::StatusOr<std::string> FetchAsset(const std::string& sha256);
  // The refined pixels of the job's light `light`'s running refinement level (a blob of
  // core/bake/refined_pixels_codec.h).
  absl::StatusOr<std::string> FetchRefinement(const std::string& job_id, const std::string& light);

 private:
  std::unique_ptr<pdsm::v1::PdsmWorkers::Stub> stub_;
  const std::string token_;
  const std::string worker_id_;
};

}  // namespace pdsm

#endif  // PDSM_WORKER_COORDINATOR_CLIENT_H_
