// Progress on stderr: a redrawn bar with ETA on a terminal, plain lines every 10% otherwise
// (logs and CI keep readable output).
#ifndef PDSM_CLIENT_PROGRESS_REPORTER_H_
#define PDSM_CLIENT_PROGRESS_REPORTER_H_

#include <cstdint>
#include <string>

namespace pdsm {

class ProgressReporter {
 public:
  explicit ProgressReporter(std::string label);
  // Not thread-safe: callers serialize.
  void Update(int64_t done, int64_t total, double seconds);
  void Finish();

 private:
  std::string label_;
  bool tty_;
  int last_decile_ = -1;
  bool drawn_ = false;
};

}  // namespace pdsm

#endif  // PDSM_CLIENT_PROGRESS_REPORTER_H_
