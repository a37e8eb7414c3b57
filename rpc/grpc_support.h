// The glue every gRPC side of pdsm shares: absl::Status <-> grpc::Status (codes map 1:1, so
// this is the one place statuses cross the wire), bearer tokens, and channel credentials.
#ifndef PDSM_RPC_GRPC_SUPPORT_H_
#define PDSM_RPC_GRPC_SUPPORT_H_

#include <chrono>
#include <memory>
#include <string>

#include <grpcpp/grpcpp.h>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace pdsm {

// A message longer than kMaxStatusMessageBytes is cut there (with its full length appended):
// it travels as metadata, which clients refuse past a few KiB, whatever a request made it echo.
inline constexpr size_t kMaxStatusMessageBytes = 2048;
grpc::Status ToGrpcStatus(const absl::Status& status);
absl::Status FromGrpcStatus(const grpc::Status& status);

// Largest message either side accepts by default: a task result of a 64x64 tile with many
// events per pixel, with room; the coordinator can lower it (--max-message-bytes).
inline constexpr int kDefaultMaxMessageBytes = 64 << 20;
// Assets and PDSM files travel in chunks of this size.
inline constexpr size_t kChunkBytes = 1 << 20;

// A secret read from a file: the first line, surrounding whitespace removed.
// INVALID_ARGUMENT naming the flag and file when it is missing, unreadable or empty.
absl::StatusOr<std::string> ReadTokenFile(const std::string& flag, const std::string& path);

// Where and how to reach the coordinator.
struct ConnectionOptions {
  std::string address;      // host:port
  std::string tls_ca_path;  // PEM roots to trust; empty: plaintext
  // The token is not part of the channel: PrepareCall puts it on each call.
};

// A channel to `address`, TLS when a CA file is given. INVALID_ARGUMENT naming the flag.
absl::StatusOr<std::shared_ptr<grpc::Channel>> MakeChannel(const ConnectionOptions& options);

// Sets the bearer token and a deadline `timeout` from now on a call.
void PrepareCall(grpc::ClientContext* context, const std::string& token,
                 std::chrono::milliseconds timeout);

}  // namespace pdsm

#endif  // PDSM_RPC_GRPC_SUPPORT_H_
