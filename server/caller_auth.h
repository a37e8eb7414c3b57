// Who may call what. Three secrets, each optional:
//   - the client token: the whole job API (submit, cancel, fetch, query, tiles, and the reads);
//   - the monitoring token: only the job API's read-only state calls (GetJob, ListJobs,
//     WatchJob, GetStats), so a dashboard or an on-call operator can follow the farm without a
//     credential that submits, cancels or reads any job's contents;
//   - the worker token: the worker API.
// They are separate secrets, so a leaked worker or monitoring credential cannot read or cancel
// jobs. A call with no valid token is UNAUTHENTICATED; a valid token that does not grant the
// call is PERMISSION_DENIED. An API whose token is not configured is open (the coordinator logs
// a warning at start); the read-only calls follow the client token (open when it is unset).
// Thread safety: immutable after construction; Check may be called from any thread.
#ifndef PDSM_SERVER_CALLER_AUTH_H_
#define PDSM_SERVER_CALLER_AUTH_H_

#include <string>

#include <grpcpp/grpcpp.h>

namespace pdsm {

enum class Audience {
  kClient,   // job API calls that change jobs or read their contents
  kMonitor,  // job API calls that read job state and stats only
  kWorker,   // the worker API
};

struct CallerTokens {
  std::string client;   // empty: the job API is open
  std::string monitor;  // empty: no monitoring token (the read-only calls want the client's)
  std::string worker;   // empty: the worker API is open
};

class CallerAuth {
 public:
  explicit CallerAuth(CallerTokens tokens) : tokens_(std::move(tokens)) {}

  grpc::Status Check(const grpc::CallbackServerContext* context, Audience audience) const;

 private:
  CallerTokens tokens_;
};

}  // namespace pdsm

#endif  // PDSM_SERVER_CALLER_AUTH_H_
