// A Prometheus-style histogram of one quantity (seconds of a task, say): fixed upper bounds,
// a count per bucket, the sum and the count of observations. Observe() is lock-free and may be
// called from any thread; Snapshot() reads a consistent-enough copy (each field atomically;
// a scrape racing an observation may see the count one ahead of a bucket, which Prometheus
// tolerates: buckets are cumulative and monotonic over time either way).
#ifndef PDSM_METRICS_HISTOGRAM_H_
#define PDSM_METRICS_HISTOGRAM_H_

#include <atomic>
#include <cstdint>
#include <memory>
#include <vector>

namespace pdsm {

class Histogram {
 public:
  struct Snapshot {
    std::vector<double> upper_bounds;  // ascending; +Inf is implicit
    std::vector<uint64_t> cumulative;  // per bound, observations <= it; then the +Inf total
    double sum = 0;
    uint64_t count = 0;
  };

  // REQUIRES: upper_bounds ascending, finite.
  explicit Histogram(std::vector<double> upper_bounds)
      : bounds_(std::move(upper_bounds)),
        buckets_(std::make_unique<std::atomic<uint64_t>[]>(bounds_.size() + 1)) {}

  // NaN is not recorded (it would poison the sum).
  void Observe(double value) {
    if (value != value) return;
    size_t bucket = 0;
    while (bucket < bounds_.size() && value > bounds_[bucket]) ++bucket;
    buckets_[bucket].fetch_add(1, std::memory_order_relaxed);
    // A CAS loop: std::atomic<double>::fetch_add is C++20 but not in every standard library.
    double sum = sum_.load(std::memory_order_relaxed);
    while (!sum_.compare_exchange_weak(sum, sum + value, std::memory_order_relaxed)) {
    }
  }

  Snapshot Read() const {
    Snapshot s;
    s.upper_bounds = bounds_;
    uint64_t running = 0;
    for (size_t b = 0; b <= bounds_.size(); ++b) {
      running += buckets_[b].load(std::memory_order_relaxed);
      s.cumulative.push_back(running);
    }
    s.count = running;
    s.sum = sum_.load(std::memory_order_relaxed);
    return s;
  }

 private:
  const std::vector<double> bounds_;
  std::unique_ptr<std::atomic<uint64_t>[]> buckets_;  // bounds_.size() + 1, the last is +Inf
  std::atomic<double> sum_{0.0};
};

// Bounds for durations in seconds, from 10 ms to about 10 minutes (factors of about 2.5).
inline std::vector<double> SecondsBuckets() {
  return {0.01, 0.025, 0.05, 0.1, 0.25, 0.5, 1, 2.5, 5, 10, 25, 50, 100, 250, 600};
}

}  // namespace pdsm

#endif  // PDSM_METRICS_HISTOGRAM_H_
