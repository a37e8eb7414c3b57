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
  const std::string& wanted = audience == Audience::kClient ? client_token_ : worker_token_;
  const std::string& other = audience == Audience::kClient ? worker_token_ : client_token_;
  if (wanted.empty()) return grpc::Status::OK;
  const absl::string_view token = BearerToken(context);
  if (SameSecret(token, wanted)) return grpc::Status::OK;
  if (SameSecret(token, other)) {
    return grpc::Status(grpc::StatusCode::PERMISSION_DENIED,
                        audience == Audience::kClient
                            ? "a worker token may not call the job API"
                            : "a client token may not call the worker API");
  }
  return grpc::Status(
      grpc::StatusCode::UNAUTHENTICATED,
      token.empty() ? "missing \"authorization: Bearer <token>\"" : "invalid token");
}

}  // namespace pdsm
