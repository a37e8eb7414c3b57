#include "server/plan_budget.h"

#include <algorithm>

#include "absl/strings/str_format.h"

namespace pdsm {
namespace {

double Mib(int64_t bytes) { return static_cast<double>(bytes) / double{1 << 20}; }

}  // namespace

PlanBudget::PlanBudget(int64_t limit_bytes) : limit_bytes_(limit_bytes) {}

bool PlanBudget::Fits(int64_t bytes) const {
  return held_.empty() || held_bytes_ + std::max<int64_t>(0, bytes) <= limit_bytes_;
}

void PlanBudget::Wait(const Entry& job) {
  const WaitKey key = KeyOf(job);
  waiting_[key] = job;
  waiting_keys_[job.job_id] = key;
}

bool PlanBudget::Admit(const Entry& job) {
  absl::MutexLock lock(&mu_);
  const bool waits_behind = !waiting_.empty() && waiting_.begin()->first < KeyOf(job);
  if (waits_behind || !Fits(job.bytes)) {
    Wait(job);
    return false;
  }
  held_[job.job_id] = Held{.entry = job, .bytes = job.bytes, .activating = true};
  held_bytes_ += job.bytes;
  return true;
}

void PlanBudget::Enqueue(const Entry& job) {
  absl::MutexLock lock(&mu_);
  Wait(job);
}

std::optional<PlanBudget::Entry> PlanBudget::TakeNext() {
  absl::MutexLock lock(&mu_);
  if (waiting_.empty()) return std::nullopt;
  const Entry first = waiting_.begin()->second;
  if (!Fits(first.bytes)) return std::nullopt;
  waiting_.erase(waiting_.begin());
  waiting_keys_.erase(first.job_id);
  const int64_t reserved = std::max<int64_t>(0, first.bytes);
  held_[first.job_id] = Held{.entry = first, .bytes = reserved, .activating = true};
  held_bytes_ += reserved;
  return first;
}

PlanBudget::Verdict PlanBudget::Planned(const std::string& job_id, int64_t bytes) {
  absl::MutexLock lock(&mu_);
  const auto it = held_.find(job_id);
  if (it == held_.end()) return Verdict::kCancelled;  // released meanwhile
  Held& held = it->second;
  held_bytes_ -= held.bytes;
  if (held.cancel_requested) {
    held_.erase(it);
    return Verdict::kCancelled;
  }
  const bool alone = held_.size() == 1;
  if (!alone && held_bytes_ + bytes > limit_bytes_) {
    // Back in the queue with what it now needs, in its place: first, as nothing passed it.
    Entry entry = held.entry;
    entry.bytes = bytes;
    held_.erase(it);
    Wait(entry);
    return Verdict::kWait;
  }
  held.bytes = bytes;
  held_bytes_ += bytes;
  return Verdict::kActivate;
}

bool PlanBudget::Activated(const std::string& job_id) {
  absl::MutexLock lock(&mu_);
  const auto it = held_.find(job_id);
  if (it == held_.end()) return false;
  it->second.activating = false;
  return it->second.cancel_requested;
}

void PlanBudget::Grow(const std::string& job_id, int64_t bytes) {
  absl::MutexLock lock(&mu_);
  const auto it = held_.find(job_id);
  if (it == held_.end() || bytes <= 0) return;
  it->second.bytes += bytes;
  held_bytes_ += bytes;
}

void PlanBudget::Release(const std::string& job_id) {
  absl::MutexLock lock(&mu_);
  if (const auto it = held_.find(job_id); it != held_.end()) {
    held_bytes_ -= it->second.bytes;
    held_.erase(it);
  }
  if (const auto it = waiting_keys_.find(job_id); it != waiting_keys_.end()) {
    waiting_.erase(it->second);
    waiting_keys_.erase(it);
  }
}

PlanBudget::CancelOutcome PlanBudget::Cancel(const std::string& job_id) {
  absl::MutexLock lock(&mu_);
  if (const auto it = waiting_keys_.find(job_id); it != waiting_keys_.end()) {
    waiting_.erase(it->second);
    waiting_keys_.erase(it);
    return CancelOutcome::kWasWaiting;
  }
  const auto it = held_.find(job_id);
  if (it == held_.end() || !it->second.activating) return CancelOutcome::kNotHere;
  it->second.cancel_requested = true;
  return CancelOutcome::kActivating;
}

bool PlanBudget::HasWaiting() const {
  absl::MutexLock lock(&mu_);
  return !waiting_.empty();
}

std::string PlanBudget::WaitingReason(const std::string& job_id) const {
  absl::MutexLock lock(&mu_);
  const auto key = waiting_keys_.find(job_id);
  if (key == waiting_keys_.end()) return "";
  const auto it = waiting_.find(key->second);
  const int ahead = static_cast<int>(std::distance(waiting_.begin(), it));
  const std::string needs = it->second.bytes < 0
                                ? std::string("it is planned again when its turn comes")
                                : absl::StrFormat("its plans need %.1f MiB", Mib(it->second.bytes));
  return absl::StrFormat(
      "waiting for coordinator memory: %s, beside %.1f MiB held by %d running job%s (limit "
      "%.0f MiB, --max-planned-mib); %d job%s wait%s ahead of it",
      needs, Mib(held_bytes_), held_.size(), held_.size() == 1 ? "" : "s", Mib(limit_bytes_), ahead,
      ahead == 1 ? "" : "s", ahead == 1 ? "s" : "");
}

PlanBudget::Usage PlanBudget::usage() const {
  absl::MutexLock lock(&mu_);
  return Usage{.held_bytes = held_bytes_,
               .limit_bytes = limit_bytes_,
               .jobs_held = static_cast<int>(held_.size()),
               .jobs_waiting = static_cast<int>(waiting_.size())};
}

}  // namespace pdsm
