// Exponential backoff with jitter, for a client retrying a call that failed for a reason that
// may pass (the coordinator restarting, a deadline under load). The delay doubles from
// `initial` up to `cap`; each wait is drawn uniformly in [delay / 2, delay] ("equal jitter"),
// so a farm of workers that lost the coordinator together does not come back in lockstep,
// while no wait is shorter than half the schedule. Not thread-safe: one per retrying loop.
#ifndef PDSM_CORE_UTIL_BACKOFF_H_
#define PDSM_CORE_UTIL_BACKOFF_H_

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <random>

namespace pdsm {

class Backoff {
 public:
  // REQUIRES: 0 < initial <= cap. `seed` fixes the jitter (tests); workers seed it randomly.
  Backoff(std::chrono::milliseconds initial, std::chrono::milliseconds cap, uint64_t seed)
      : initial_(initial), cap_(cap), delay_(initial), rng_(seed) {}

  // The next wait, then doubles the schedule (up to the cap).
  std::chrono::milliseconds Next() {
    const int64_t d = delay_.count();
    std::uniform_int_distribution<int64_t> jitter(d / 2, d);
    delay_ = std::min(cap_, delay_ * 2);
    return std::chrono::milliseconds(jitter(rng_));
  }
  // After a success: the next failure waits about `initial` again.
  void Reset() { delay_ = initial_; }

 private:
  const std::chrono::milliseconds initial_, cap_;
  std::chrono::milliseconds delay_;
  std::mt19937_64 rng_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_BACKOFF_H_
