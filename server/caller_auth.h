// Who may call what. The job API wants the client token, the worker API the worker token
// (separate secrets, so a leaked worker credential cannot read or cancel jobs). A call with
// no valid token is UNAUTHENTICATED; a valid token of the other kind is PERMISSION_DENIED.
// An API whose token is not configured is open (the coordinator logs a warning at start).
#ifndef PDSM_SERVER_CALLER_AUTH_H_
#define PDSM_SERVER_CALLER_AUTH_H_

#include <string>

#include <grpcpp/grpcpp.h>

namespace pdsm {

enum class Audience { kClient, kWorker };

class CallerAuth {
 public:
  CallerAuth(std::string client_token, std::string worker_token)
      : client_token_(std::move(client_token)), worker_token_(std::move(worker_token)) {}

  grpc::Status Check(const grpc::CallbackServerContext* context, Audience audience) const;

 private:
  std::string client_token_;  // empty: the job API is open
  std::string worker_token_;  // empty: the worker API is open
};

}  // namespace pdsm

#endif  // PDSM_SERVER_CALLER_AUTH_H_
