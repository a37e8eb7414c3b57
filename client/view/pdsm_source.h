// Where the viewer's PDSM comes from: a file (--pdsm) or a job on a coordinator (--server
// --job), fetched over gRPC once the job has finished.
#ifndef PDSM_CLIENT_VIEW_PDSM_SOURCE_H_
#define PDSM_CLIENT_VIEW_PDSM_SOURCE_H_

#include <cstdint>
#include <memory>
#include <string>

#include "absl/status/statusor.h"
#include "client/service/service_connection.h"
#include "client/view/pdsm_tiles.h"
#include "core/pdsm/pdsm_image.h"

namespace pdsm::view {

// Reads light `light` of a PDSM file (empty: its only light; ReadPdsm). Errors name the file:
// NOT_FOUND (also: no such light), DATA_LOSS (corrupt or not a PDSM), FAILED_PRECONDITION (a
// format version this build does not read, or several lights and no `light`).
absl::StatusOr<PdsmImage> LoadPdsmFile(const std::string& path, const std::string& light = "");

// Waits for `job_id` with WatchJob, printing a progress line on stderr, then downloads its
// PDSM (FetchPdsm) into a temporary file and opens its light `light` for streaming (as
// PdsmTiles::OpenFile; the file is unlinked once open, so nothing is left behind).
// FAILED_PRECONDITION when the job failed or was cancelled; the coordinator's errors as
// `pdsm fetch` reports them.
absl::StatusOr<std::shared_ptr<PdsmTiles>> FetchJobPdsm(const ServiceFlags& service,
                                                        const std::string& job_id,
                                                        const std::string& light,
                                                        int64_t cache_bytes);

}  // namespace pdsm::view

#endif  // PDSM_CLIENT_VIEW_PDSM_SOURCE_H_
