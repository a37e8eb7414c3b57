// How `pdsm` subcommands reach a coordinator: the --server, --token-file and --tls-ca flags,
// and a job-API stub that sends the token with every call.
#ifndef PDSM_CLIENT_SERVICE_SERVICE_CONNECTION_H_
#define PDSM_CLIENT_SERVICE_SERVICE_CONNECTION_H_

#include <chrono>
#include <cstdint>
#include <memory>
#include <string>

#include <CLI/CLI.hpp>

#include "absl/status/statusor.h"
#include "core/util/file_system.h"
#include "pdsm/v1/jobs.grpc.pb.h"

namespace pdsm {

struct ServiceFlags {
  std::string server;      // host:port; $PDSM_SERVER when the flag is absent
  std::string token_file;  // the client token; $PDSM_TOKEN_FILE when absent
  std::string tls_ca;      // PEM roots: connect with TLS
};

// `required`: --server must be given (or $PDSM_SERVER set).
void AddServiceFlags(CLI::App* command, ServiceFlags* flags, bool required = true);

struct ServiceConnection {
  std::unique_ptr<pdsm::v1::PdsmJobs::Stub> stub;
  std::string token;
  // A context with the token and a deadline; every call of the CLI uses one.
  std::unique_ptr<grpc::ClientContext> Call(
      std::chrono::milliseconds timeout = std::chrono::seconds(30)) const;
};

absl::StatusOr<ServiceConnection> Connect(const ServiceFlags& flags);

// A failed call as the user should read it: "<what>: <coordinator's message>", with a hint
// for the codes that mean the connection or the token is wrong.
absl::Status CallError(const std::string& what, const grpc::Status& status,
                       const std::string& server);

// Streams a finished job's PDSM (FetchPdsm) into `path` through an AtomicFile
// (core/util/atomic_file.h): the file appears at `path` only once every announced byte has
// arrived and is synced; on any failure `path` is left as it was and no temporary file
// remains. Errors: the call's (CallError), DATA_LOSS when fewer bytes arrive than announced,
// the FileSystem's when writing fails (RESOURCE_EXHAUSTED for a full disk; the call is then
// cancelled). `fs` null means FileSystem::Default(). Returns the bytes received.
absl::StatusOr<uint64_t> DownloadPdsm(const ServiceConnection& c, const ServiceFlags& service,
                                      const std::string& job_id, const std::string& path,
                                      FileSystem* fs = nullptr);

// DownloadPdsm's second half, from an open FetchPdsm stream (a seam for tests): reads every
// chunk of `reader`, cancelling `context` if writing fails, and finishes the call. `server`
// goes into error hints.
absl::StatusOr<uint64_t> ReceivePdsm(grpc::ClientContext* context,
                                     grpc::ClientReaderInterface<pdsm::v1::PdsmChunk>* reader,
                                     const std::string& job_id, const std::string& server,
                                     const std::string& path, FileSystem* fs = nullptr);

}  // namespace pdsm

#endif  // PDSM_CLIENT_SERVICE_SERVICE_CONNECTION_H_
