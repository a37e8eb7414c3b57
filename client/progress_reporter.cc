#include "client/progress_reporter.h"

#include <unistd.h>

#include <algorithm>
#include <cstdio>

namespace pdsm {

ProgressReporter::ProgressReporter(std::string label, std::string unit)
    : label_(std::move(label)), unit_(std::move(unit)), tty_(isatty(STDERR_FILENO) != 0) {}

void ProgressReporter::Update(int64_t done, int64_t total, double seconds,
                              std::optional<double> eta_seconds) {
  const double fraction = total > 0 ? static_cast<double>(done) / total : 1.0;
  const double eta = eta_seconds ? std::max(0.0, *eta_seconds)
                     : done > 0  ? seconds * (1.0 - fraction) / fraction
                                 : 0.0;
  if (tty_) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(fraction * kWidth);
    std::string bar(filled, '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r%s [%s] %3.0f%% %lld/%lld %s, %.1fs, ETA %.0fs ", label_.c_str(),
                 bar.c_str(), 100 * fraction, static_cast<long long>(done),
                 static_cast<long long>(total), unit_.c_str(), seconds, eta);
    std::fflush(stderr);
    drawn_ = true;
    return;
  }
  const int decile = static_cast<int>(fraction * 10);
  if (decile == last_decile_) return;
  last_decile_ = decile;
  std::fprintf(stderr, "%s: %3.0f%% (%lld/%lld %s, %.1fs, ETA %.0fs)\n", label_.c_str(),
               100 * fraction, static_cast<long long>(done), static_cast<long long>(total),
               unit_.c_str(), seconds, eta);
}

void ProgressReporter::Finish() {
  if (tty_ && drawn_) std::fputc('\n', stderr);
}

}  // namespace pdsm
