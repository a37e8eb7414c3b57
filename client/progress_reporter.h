// Progress on stderr: a redrawn bar with ETA on a terminal, plain lines every 10% otherwise
// (logs and CI keep readable output).
#ifndef PDSM_CLIENT_PROGRESS_REPORTER_H_
#define PDSM_CLIENT_PROGRESS_REPORTER_H_

#include <cstdint>
#include <optional>
#include <string>

namespace pdsm {

class ProgressReporter {
 public:
  // `unit` names what done/total count ("tasks", "samples").
  explicit ProgressReporter(std::string label, std::string unit = "tasks");
  // Not thread-safe: callers serialize.
  // `eta_seconds`: the caller's estimate (e.g. the coordinator's); by default extrapolated
  // from `seconds`. Negative: unknown.
  void Update(int64_t done, int64_t total, double seconds,
              std::optional<double> eta_seconds = std::nullopt);
  void Finish();

 private:
  std::string label_;
  std::string unit_;
  bool tty_;
  int last_decile_ = -1;
  bool drawn_ = false;
};

}  // namespace pdsm

#endif  // PDSM_CLIENT_PROGRESS_REPORTER_H_
