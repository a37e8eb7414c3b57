#include "server/watch_hub.h"

#include <chrono>

#include "rpc/grpc_support.h"

namespace pdsm {
namespace {

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

  // Called by the hub with its mutex held.
  void Poll(std::chrono::steady_clock::time_point now) {
    if (writing_ || finished_) return;
    if (sent_any_ && Ended(sent_)) return Finish(grpc::Status::OK);  // the last word was said
    absl::StatusOr<pdsm::v1::Job> job = hub_->coordinator_->GetJob(job_id_);
    if (!job.ok()) return Finish(ToGrpcStatus(job.status()));
    if (sent_any_ && SameProgress(*job, sent_) && now - sent_at_ < kHeartbeat) return;
    sent_ = *std::move(job);
    sent_any_ = true;
    sent_at_ = now;
    writing_ = true;
    StartWrite(&sent_);
  }

  void Finish(const grpc::Status& status) {
    finished_ = true;
    grpc::ServerWriteReactor<pdsm::v1::Job>::Finish(status);
  }

  void OnWriteDone(bool ok) override {
    std::lock_guard<std::mutex> lock(hub_->mu_);
    writing_ = false;
    if (finished_) return;
    if (!ok) return Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "write failed"));
    if (hub_->stopping_) {
      Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "the coordinator is stopping"));
    }
  }

  void OnDone() override {
    {
      std::lock_guard<std::mutex> lock(hub_->mu_);
      hub_->watchers_.erase(this);
    }
    delete this;
  }

  bool writing_ = false;
  bool finished_ = false;

 private:
  WatchHub* hub_;
  const std::string job_id_;
  pdsm::v1::Job sent_;
  bool sent_any_ = false;
  std::chrono::steady_clock::time_point sent_at_;
};

WatchHub::WatchHub(Coordinator* coordinator)
    : coordinator_(coordinator), thread_([this] { Loop(); }) {}

WatchHub::~WatchHub() {
  Shutdown();
}

grpc::ServerWriteReactor<pdsm::v1::Job>* WatchHub::Watch(const std::string& job_id) {
  auto* watcher = new Watcher(this, job_id);
  std::lock_guard<std::mutex> lock(mu_);
  if (stopping_) {
    watcher->Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "the coordinator is stopping"));
  } else {
    watchers_.insert(watcher);
    watcher->Poll(std::chrono::steady_clock::now());  // the first state at once
  }
  return watcher;
}

void WatchHub::Loop() {
  std::unique_lock<std::mutex> lock(mu_);
  while (!stopping_) {
    cv_.wait_for(lock, kPollPeriod);
    if (stopping_) break;
    const auto now = std::chrono::steady_clock::now();
    for (Watcher* w : watchers_) w->Poll(now);
  }
}

void WatchHub::Shutdown() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (stopping_) return;
    stopping_ = true;
    for (Watcher* w : watchers_) {
      if (!w->finished_ && !w->writing_) {
        w->Finish(grpc::Status(grpc::StatusCode::UNAVAILABLE, "the coordinator is stopping"));
      }
    }
  }
  cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

}  // namespace pdsm
