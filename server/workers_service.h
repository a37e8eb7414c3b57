// The worker API (pdsm.v1.PdsmWorkers) over the Coordinator, with gRPC's callback API.
#ifndef PDSM_SERVER_WORKERS_SERVICE_H_
#define PDSM_SERVER_WORKERS_SERVICE_H_

#include "pdsm/v1/workers.grpc.pb.h"
#include "server/caller_auth.h"
#include "server/coordinator.h"

namespace pdsm {

class WorkersService final : public pdsm::v1::PdsmWorkers::CallbackService {
 public:
  // `coordinator` and `auth` must outlive the service.
  WorkersService(Coordinator* coordinator, const CallerAuth* auth)
      : coordinator_(coordinator), auth_(auth) {}

  grpc::ServerUnaryReactor* LeaseTask(grpc::CallbackServerContext* context,
                                      const pdsm::v1::LeaseTaskRequest* request,
                                      pdsm::v1::LeaseTaskResponse* response) override;
  grpc::ServerUnaryReactor* ExtendLease(grpc::CallbackServerContext* context,
                                        const pdsm::v1::ExtendLeaseRequest* request,
                                        pdsm::v1::ExtendLeaseResponse* response) override;
  grpc::ServerUnaryReactor* ReportResult(grpc::CallbackServerContext* context,
                                         const pdsm::v1::ReportResultRequest* request,
                                         pdsm::v1::ReportResultResponse* response) override;
  grpc::ServerUnaryReactor* ReportFailure(grpc::CallbackServerContext* context,
                                          const pdsm::v1::ReportFailureRequest* request,
                                          pdsm::v1::ReportFailureResponse* response) override;
  grpc::ServerUnaryReactor* SignOff(grpc::CallbackServerContext* context,
                                    const pdsm::v1::SignOffRequest* request,
                                    pdsm::v1::SignOffResponse* response) override;
  grpc::ServerUnaryReactor* GetJobScene(grpc::CallbackServerContext* context,
                                        const pdsm::v1::GetJobSceneRequest* request,
                                        pdsm::v1::GetJobSceneResponse* response) override;
  grpc::ServerWriteReactor<pdsm::v1::AssetData>* FetchAsset(
      grpc::CallbackServerContext* context, const pdsm::v1::FetchAssetRequest* request) override;
  grpc::ServerWriteReactor<pdsm::v1::AssetData>* FetchRefinement(
      grpc::CallbackServerContext* context,
      const pdsm::v1::FetchRefinementRequest* request) override;

 private:
  Coordinator* coordinator_;
  const CallerAuth* auth_;
};

}  // namespace pdsm

#endif  // PDSM_SERVER_WORKERS_SERVICE_H_
