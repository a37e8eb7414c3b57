// One pool of threads for every part of pdsm that runs work in parallel (pbrt-v4's ParallelFor
// and leveldb's Env::Schedule are the models): the local bake's task runners, the
// coordinator's tile assembly, the remote worker's pull loops, the references' point loops.
// Work items run in the order they were posted, each on one of the queue's threads.
//
// Thread-safe: any thread may Post, Wait or Stop. A work item may Post more work; it must not
// Wait on its own queue (it would wait for itself).
#ifndef PDSM_CORE_UTIL_WORK_QUEUE_H_
#define PDSM_CORE_UTIL_WORK_QUEUE_H_

#include <cstddef>
#include <deque>
#include <functional>
#include <thread>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"

namespace pdsm {

class WorkQueue {
 public:
  // Starts `threads` threads (at least one).
  explicit WorkQueue(int threads);
  // Stop(): work not yet started is dropped, running work finishes.
  ~WorkQueue();
  WorkQueue(const WorkQueue&) = delete;
  WorkQueue& operator=(const WorkQueue&) = delete;

  // Queues `work`; ignored once Stop() has been called.
  void Post(std::function<void()> work);

  // Blocks until every posted item has run and been destroyed (none queued, none running).
  void Wait();

  // Drops the queued items, lets running ones finish and joins the threads. Idempotent.
  // Callers whose queued work must not be lost Wait() first.
  void Stop();

  int thread_count() const { return static_cast<int>(threads_.size()); }

 private:
  void Loop();
  bool Idle() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  bool HasWorkOrStopping() const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  mutable absl::Mutex mu_;
  std::deque<std::function<void()>> queue_ ABSL_GUARDED_BY(mu_);
  int running_ ABSL_GUARDED_BY(mu_) = 0;
  bool stopping_ ABSL_GUARDED_BY(mu_) = false;
  std::vector<std::thread> threads_;  // set by the constructor, joined by Stop()
};

// The number of threads "one per core" means: hardware_concurrency, at least 1.
int CoreCount();

// Runs `work` once on each of min(CoreCount(), max_threads) threads (at least one) and waits.
// The loops share their items through a counter of the caller's, and each writes only its
// own items' results, so results do not depend on the scheduling.
void RunOnAllCores(size_t max_threads, const std::function<void()>& work);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_WORK_QUEUE_H_
