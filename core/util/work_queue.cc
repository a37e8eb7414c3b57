#include "core/util/work_queue.h"

#include <algorithm>

namespace pdsm {

WorkQueue::WorkQueue(int threads) {
  const int n = std::max(1, threads);
  threads_.reserve(n);
  for (int i = 0; i < n; ++i) threads_.emplace_back([this] { Loop(); });
}

WorkQueue::~WorkQueue() { Stop(); }

void WorkQueue::Post(std::function<void()> work) {
  absl::MutexLock lock(&mu_);
  if (stopping_) return;
  queue_.push_back(std::move(work));
}

void WorkQueue::Wait() {
  absl::MutexLock lock(&mu_);
  mu_.Await(absl::Condition(this, &WorkQueue::Idle));
}

void WorkQueue::Stop() {
  {
    absl::MutexLock lock(&mu_);
    if (stopping_ && threads_.empty()) return;
    stopping_ = true;
    queue_.clear();
  }
  for (std::thread& t : threads_) {
    if (t.joinable()) t.join();
  }
  threads_.clear();
}

bool WorkQueue::Idle() const { return queue_.empty() && running_ == 0; }

bool WorkQueue::HasWorkOrStopping() const { return stopping_ || !queue_.empty(); }

void WorkQueue::Loop() {
  for (;;) {
    std::function<void()> work;
    {
      absl::MutexLock lock(&mu_);
      mu_.Await(absl::Condition(this, &WorkQueue::HasWorkOrStopping));
      if (queue_.empty()) return;  // stopping, nothing left to start
      work = std::move(queue_.front());
      queue_.pop_front();
      ++running_;
    }
    work();
    // The item's captures go before it counts as done: Wait() promises that nothing posted
    // still runs, and a capture's destructor (the last reference to a job, say) is part of it.
    work = nullptr;
    absl::MutexLock lock(&mu_);
    --running_;
  }
}

int CoreCount() { return std::max(1u, std::thread::hardware_concurrency()); }

void RunOnAllCores(size_t max_threads, const std::function<void()>& work) {
  const int threads =
      static_cast<int>(std::clamp<size_t>(CoreCount(), 1, std::max<size_t>(max_threads, 1)));
  WorkQueue queue(threads);
  for (int t = 0; t < threads; ++t) queue.Post(work);
  queue.Wait();
}

}  // namespace pdsm
