// How the services end a call that is answered at once: a unary call finished with a status,
// or a stream refused before it starts (a failed token check). One place for both services.
#ifndef PDSM_SERVER_CALL_REPLIES_H_
#define PDSM_SERVER_CALL_REPLIES_H_

#include <grpcpp/grpcpp.h>

#include "absl/status/status.h"
#include "rpc/grpc_support.h"

namespace pdsm {

inline grpc::ServerUnaryReactor* Answer(grpc::CallbackServerContext* context,
                                        const grpc::Status& status) {
  grpc::ServerUnaryReactor* reactor = context->DefaultReactor();
  reactor->Finish(status);
  return reactor;
}

inline grpc::ServerUnaryReactor* Answer(grpc::CallbackServerContext* context,
                                        const absl::Status& status) {
  return Answer(context, ToGrpcStatus(status));
}

// A streaming reactor (ServerReadReactor<T> or ServerWriteReactor<T>) that ends the call with
// `status` at once and deletes itself when gRPC is done with it.
template <typename Reactor>
class RefusedStream final : public Reactor {
 public:
  explicit RefusedStream(const grpc::Status& status) { this->Finish(status); }
  void OnDone() override { delete this; }
};

}  // namespace pdsm

#endif  // PDSM_SERVER_CALL_REPLIES_H_
