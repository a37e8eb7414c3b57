// The job API (pdsm.v1.PdsmJobs) over the Coordinator, with gRPC's callback API: each call
// checks the caller's token, translates messages, and answers. Streams (asset upload, watch,
// fetch) are reactors; watchers are woken by one hub thread instead of a thread each.
#ifndef PDSM_SERVER_JOBS_SERVICE_H_
#define PDSM_SERVER_JOBS_SERVICE_H_

#include <memory>

#include "pdsm/v1/jobs.grpc.pb.h"
#include "server/caller_auth.h"
#include "server/coordinator.h"

namespace pdsm {

class WatchHub;

class JobsService final : public pdsm::v1::PdsmJobs::CallbackService {
 public:
  // `coordinator` and `auth` must outlive the service.
  JobsService(Coordinator* coordinator, const CallerAuth* auth);
  ~JobsService() override;

  // Ends every open watch (the server is shutting down).
  void Shutdown();

  grpc::ServerUnaryReactor* FindMissingAssets(
      grpc::CallbackServerContext* context, const pdsm::v1::FindMissingAssetsRequest* request,
      pdsm::v1::FindMissingAssetsResponse* response) override;
  grpc::ServerReadReactor<pdsm::v1::AssetChunk>* UploadAsset(
      grpc::CallbackServerContext* context, pdsm::v1::UploadAssetResponse* response) override;
  grpc::ServerUnaryReactor* SubmitBake(grpc::CallbackServerContext* context,
                                       const pdsm::v1::SubmitBakeRequest* request,
                                       pdsm::v1::Job* response) override;
  grpc::ServerUnaryReactor* GetJob(grpc::CallbackServerContext* context,
                                   const pdsm::v1::GetJobRequest* request,
                                   pdsm::v1::Job* response) override;
  grpc::ServerUnaryReactor* ListJobs(grpc::CallbackServerContext* context,
                                     const pdsm::v1::ListJobsRequest* request,
                                     pdsm::v1::ListJobsResponse* response) override;
  grpc::ServerWriteReactor<pdsm::v1::Job>* WatchJob(
      grpc::CallbackServerContext* context, const pdsm::v1::GetJobRequest* request) override;
  grpc::ServerUnaryReactor* CancelJob(grpc::CallbackServerContext* context,
                                      const pdsm::v1::GetJobRequest* request,
                                      pdsm::v1::Job* response) override;
  grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>* FetchPdsm(
      grpc::CallbackServerContext* context, const pdsm::v1::GetJobRequest* request) override;
  grpc::ServerUnaryReactor* ListFinishedTiles(grpc::CallbackServerContext* context,
                                              const pdsm::v1::ListFinishedTilesRequest* request,
                                              pdsm::v1::FinishedTiles* response) override;
  grpc::ServerWriteReactor<pdsm::v1::PdsmChunk>* FetchTile(
      grpc::CallbackServerContext* context, const pdsm::v1::FetchTileRequest* request) override;
  grpc::ServerUnaryReactor* QueryAttenuation(grpc::CallbackServerContext* context,
                                             const pdsm::v1::QueryAttenuationRequest* request,
                                             pdsm::v1::QueryAttenuationResponse* response) override;
  grpc::ServerUnaryReactor* GetStats(grpc::CallbackServerContext* context,
                                     const pdsm::v1::GetStatsRequest* request,
                                     pdsm::v1::Stats* response) override;

 private:
  Coordinator* coordinator_;
  const CallerAuth* auth_;
  std::unique_ptr<WatchHub> watch_hub_;
};

}  // namespace pdsm

#endif  // PDSM_SERVER_JOBS_SERVICE_H_
