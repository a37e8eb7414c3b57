#include "server/caller_auth.h"

#include <openssl/crypto.h>

#include "absl/strings/match.h"
#include "absl/strings/string_view.h"

namespace pdsm {
namespace {

// Constant-time comparison, so response timing does not reveal how much of a guess matched.
bool SameSecret(absl::string_view given, const std::string& secret) {
  if (secret.empty() || given.size() != secret.size()) return false;
  return CRYPTO_memcmp(given.data(), secret.data(), secret.size()) == 0;
}

absl::string_view BearerToken(const grpc::CallbackServerContext* context) {
  const auto& metadata = context->client_metadata();
  const auto it = metadata.find("authorization");
  if (it == metadata.end()) return {};
  absl::string_view value(it->second.data(), it->second.size());
  constexpr absl::string_view kBearer = "Bearer ";
  if (!absl::StartsWith(value, kBearer)) return {};
  return value.substr(kBearer.size());
}

}  // namespace

grpc::Status CallerAuth::Check(const grpc::CallbackServerContext* context,
                               Audience audience) const {
  const bool open = audience == Audience::kWorker ? tokens_.worker.empty() : tokens_.client.empty();
  if (open) return grpc::Status::OK;
  const absl::string_view token = BearerToken(context);
  const bool is_client = SameSecret(token, tokens_.client);
  const bool is_monitor = SameSecret(token, tokens_.monitor);
  const bool is_worker = SameSecret(token, tokens_.worker);
  switch (audience) {
    case Audience::kClient:
      if (is_client) return grpc::Status::OK;
      break;
    case Audience::kMonitor:
      if (is_client || is_monitor) return grpc::Status::OK;
      break;
    case Audience::kWorker:
      if (is_worker) return grpc::Status::OK;
      break;
  }
  const auto denied = [](const char* why) {
    return grpc::Status(grpc::StatusCode::PERMISSION_DENIED, why);
  };
  if (is_worker) return denied("a worker token may not call the job API");
  if (is_monitor) {
    return denied(audience == Audience::kWorker
                      ? "a monitoring token may not call the worker API"
                      : "a monitoring token may only read job state and stats (GetJob, "
                        "ListJobs, WatchJob, GetStats)");
  }
  if (is_client) return denied("a client token may not call the worker API");
  return grpc::Status(
      grpc::StatusCode::UNAUTHENTICATED,
      token.empty() ? "missing \"authorization: Bearer <token>\"" : "invalid token");
}

}  // namespace pdsm
