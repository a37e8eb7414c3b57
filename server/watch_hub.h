// WatchJob streams: one reactor per watcher, all woken by one hub thread every 100 ms. A
// watcher writes when its job changed (state, tiles, samples) or every 2 s (a fresh ETA), and
// finishes after writing an ended job. Fifty watchers cost one thread, not fifty, and the
// watchers of one job share one read of it per round: a thousand watchers of 40 jobs read
// the job store 40 times per round, not a thousand.
#ifndef PDSM_SERVER_WATCH_HUB_H_
#define PDSM_SERVER_WATCH_HUB_H_

#include <set>
#include <string>
#include <thread>

#include <grpcpp/grpcpp.h>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"
#include "pdsm/v1/jobs.pb.h"
#include "server/coordinator.h"

namespace pdsm {

class WatchHub {
 public:
  explicit WatchHub(Coordinator* coordinator);
  ~WatchHub();  // REQUIRES: Shutdown() called and the server drained

  // A reactor for one WatchJob call; it registers itself and deletes itself when done.
  grpc::ServerWriteReactor<pdsm::v1::Job>* Watch(const std::string& job_id);

  // Finishes every open watch and stops the thread.
  void Shutdown();

 private:
  class Watcher;
  void Loop();

  Coordinator* coordinator_;
  absl::Mutex mu_;  // also guards each watcher's write state (watch_hub.cc)
  absl::CondVar cv_;
  std::set<Watcher*> watchers_ ABSL_GUARDED_BY(mu_);
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  std::thread thread_;
};

}  // namespace pdsm

#endif  // PDSM_SERVER_WATCH_HUB_H_
