#include "server/job_eta.h"

#include <algorithm>

namespace pdsm {

double RateEtaSeconds(const JobProgress& progress, int64_t now_ms) {
  const int64_t left = progress.samples_total - progress.samples_done;
  if (left <= 0) return 0;
  const double elapsed_s = static_cast<double>(now_ms - progress.added_ms) / 1000.0;
  const int64_t gained = progress.samples_done - progress.samples_at_add;
  if (gained <= 0 || elapsed_s <= 0) return -1;
  return static_cast<double>(left) * elapsed_s / static_cast<double>(gained);
}

double JobEtaSeconds(double base, bool base_done, std::span<const double> levels) {
  double eta = base_done ? 0 : base;
  if (eta < 0) return -1;
  for (const double level : levels) {
    if (level < 0) return -1;
    eta = std::max(eta, level);
  }
  return eta;
}

}  // namespace pdsm
