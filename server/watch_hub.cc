#include "server/watch_hub.h"

#include <chrono>
#include <map>
#include <string>

#include "rpc/grpc_support.h"

namespace pdsm {
namespace {

using JobsRead = std::map<std::string, absl::StatusOr<pdsm::v1::Job>>;

constexpr auto kPollPeriod = std::chrono::milliseconds(100);
constexpr auto kHeartbeat = std::chrono::seconds(2);

bool Ended(const pdsm::v1::Job& job) {
  return job.state() == pdsm::v1::SUCCEEDED || job.state() == pdsm::v1::FAILED ||
         job.state() == pdsm::v1::CANCELLED;
}

bool SameProgress(const pdsm::v1::Job& a, const pdsm::v1::Job& b) {
  return a.state() == b.state() && a.tiles_done() == b.tiles_done() &&
         a.samples_done() == b.samples_done();
}

}  // namespace

// Lives from WatchJob until OnDone. `mu_` of the hub guards writing_/finished_: the hub thread
// starts writes, gRPC's threads complete them.
class WatchHub::Watcher final : public grpc::ServerWriteReactor<pdsm::v1::Job> {
 public:
  Watcher(WatchHub* hub, std::string job_id) : hub_(hub), job_id_(std::move(job_id)) {}

  // `polled`: the jobs read in this round, by id: watchers of one job share one read.
  // REQUIRES: the hub's mutex held (asserted: the analysis cannot see that hub_ is the hub).
  void Poll(std::chrono::steady_clock::time_point now, JobsRead* polled) {
    hub_->mu_.AssertHeld();
    if (writing_ || finished_) return;
    if (sent_any_ && Ended(sent_)) return Finish(grpc::Status::OK);  // the last word was said
    auto [it, first] = polled->try_emplace(job_id_, absl::UnknownError(""));
    if (first) it->second = hub_->coordinator_->GetJob(job_id_);
    const absl::StatusOr<pdsm::v1::Job>& job = it->second;
    if (!job.ok()) return Finish(ToGrpcStatus(job.status()));
    if (sent_any_ && SameProgress(*job, sent_) && now - sent_at_ < kHeartbeat) return;
    sent_ = *job;
    sent_any_ = true;
    sent_at_ = now;
    writing_ = true;
    StartWrite(&sent_);
  }

  // REQUIRES: the hub's mutex held.
  void Finish(const grpc::Status& status) {
    hub_->mu_.AssertHeld();
    finished_ = true;
    grpc::ServerWriteReactor<pdsm::v1::Job>::Finish(status);
  }

  void OnWriteDone(bool ok) override {
    absl::MutexLock lock(&hub_->mu_);
    writing_ = false;
    if (finished_) return;
    if (!ok) return Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "write failed"));
    if (hub_->stopping_) {
      Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "the coordinator is stopping"));
    }
  }

  void OnDone() override {
    {
      absl::MutexLock lock(&hub_->mu_);
      hub_->watchers_.erase(this);
    }
    delete this;
  }

  // The hub is stopping: ends the call unless a write is in flight (OnWriteDone ends it).
  // REQUIRES: the hub's mutex held.
  void FinishIfIdle() {
    hub_->mu_.AssertHeld();
    if (!finished_ && !writing_) {
      Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "the coordinator is stopping"));
    }
  }

 private:
  WatchHub* const hub_;
  bool writing_ ABSL_GUARDED_BY(hub_->mu_) = false;
  bool finished_ ABSL_GUARDED_BY(hub_->mu_) = false;
  const std::string job_id_;
  pdsm::v1::Job sent_;
  bool sent_any_ = false;
  std::chrono::steady_clock::time_point sent_at_;
};

WatchHub::WatchHub(Coordinator* coordinator)
    : coordinator_(coordinator), thread_([this] { Loop(); }) {}

WatchHub::~WatchHub() { Shutdown(); }

grpc::ServerWriteReactor<pdsm::v1::Job>* WatchHub::Watch(const std::string& job_id) {
  auto* watcher = new Watcher(this, job_id);
  absl::MutexLock lock(&mu_);
  if (stopping_) {
    watcher->Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "the coordinator is stopping"));
  } else {
    watchers_.insert(watcher);
    JobsRead polled;
    watcher->Poll(std::chrono::steady_clock::now(), &polled);  // the first state at once
  }
  return watcher;
}

void WatchHub::Loop() {
  absl::MutexLock lock(&mu_);
  while (!stopping_) {
    cv_.WaitWithTimeout(&mu_, absl::FromChrono(kPollPeriod));
    if (stopping_) break;
    const auto now = std::chrono::steady_clock::now();
    JobsRead polled;
    for (Watcher* w : watchers_) w->Poll(now, &polled);
  }
}

void WatchHub::Shutdown() {
  {
    absl::MutexLock lock(&mu_);
    if (stopping_) return;
    stopping_ = true;
    for (Watcher* w : watchers_) w->FinishIfIdle();
  }
  cv_.SignalAll();
  if (thread_.joinable()) thread_.join();
}

}  // namespace pdsm
