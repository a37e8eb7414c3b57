#include "client/view/pdsm_source.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include <unistd.h>

#include "absl/strings/str_cat.h"
#include "core/pdsm/pdsm_file.h"

namespace pdsm::view {
namespace {

// Follows the job until it ends; OK only when it succeeded.
absl::Status WaitForJob(const ServiceConnection& c, const ServiceFlags& service,
                        const std::string& job_id) {
  pdsm::v1::GetJobRequest request;
  request.set_job_id(job_id);
  auto context = c.Call(std::chrono::hours(24 * 30));  // as long as the job takes
  auto reader = c.stub->WatchJob(context.get(), request);
  pdsm::v1::Job job;
  bool any = false;
  while (reader->Read(&job)) {
    any = true;
    std::fprintf(stderr, "\rpdsm-view: job %s %s: %d/%d tiles, %.1f%%   ", job_id.c_str(),
                 pdsm::v1::JobState_Name(job.state()).c_str(), job.tiles_done(), job.tiles_total(),
                 100.0 * job.progress());
  }
  std::fprintf(stderr, "\n");
  if (grpc::Status s = reader->Finish(); !s.ok()) {
    return CallError("watching job " + job_id, s, service.server);
  }
  if (!any) return absl::UnavailableError("watching job " + job_id + ": no news from the server");
  if (job.state() != pdsm::v1::SUCCEEDED) {
    return absl::FailedPreconditionError(
        absl::StrCat("--job ", job_id, ": ", pdsm::v1::JobState_Name(job.state()),
                     job.error().empty() ? "" : ": ", job.error()));
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<PdsmImage> LoadPdsmFile(const std::string& path, const std::string& light) {
  absl::StatusOr<PdsmImage> pdsm = ReadPdsm(path, light);
  if (!pdsm.ok()) {
    const std::string message(pdsm.status().message());
    // ReadPdsm's messages usually name the file already; make sure they do.
    if (message.find(path) != std::string::npos) return pdsm.status();
    return absl::Status(pdsm.status().code(), absl::StrCat("--pdsm ", path, ": ", message));
  }
  return pdsm;
}

absl::StatusOr<std::shared_ptr<PdsmTiles>> FetchJobPdsm(const ServiceFlags& service,
                                                        const std::string& job_id,
                                                        const std::string& light,
                                                        int64_t cache_bytes) {
  absl::StatusOr<ServiceConnection> c = Connect(service);
  if (!c.ok()) return c.status();
  if (absl::Status s = WaitForJob(*c, service, job_id); !s.ok()) return s;
  const std::filesystem::path temp = std::filesystem::temp_directory_path() /
                                     absl::StrCat("pdsm-view-", job_id, "-", ::getpid(), ".exr");
  absl::Status s = DownloadPdsm(*c, service, job_id, temp.string()).status();
  // An open file outlives its name (POSIX): the tiles are read from it as frames need them.
  absl::StatusOr<std::shared_ptr<PdsmTiles>> pdsm =
      s.ok() ? PdsmTiles::OpenFile(temp.string(), light, cache_bytes)
             : absl::StatusOr<std::shared_ptr<PdsmTiles>>(s);
  std::error_code ec;
  std::filesystem::remove(temp, ec);
  return pdsm;
}

}  // namespace pdsm::view
