// Running gnuplot without files: the script goes in through a pipe, the image comes back on
// its stdout, so that the caller writes it where and how it writes every file.
#ifndef PDSM_CLIENT_MEASURE_GNUPLOT_H_
#define PDSM_CLIENT_MEASURE_GNUPLOT_H_

#include <string>

#include "absl/status/statusor.h"

namespace pdsm {

// Runs `gnuplot` (found on $PATH) on `script` and returns what it printed on stdout: the
// script must `set output` with no file name. gnuplot's stderr is this process's. The whole
// script is in the pipe before gnuplot starts, so a gnuplot that dies early cannot block or
// SIGPIPE the caller. Errors: the errno's status when it cannot be started or the script
// does not fit a pipe (about 1 MiB by default); INTERNAL when it exits non-zero or prints
// nothing. Thread-compatible.
absl::StatusOr<std::string> RunGnuplot(const std::string& script);

}  // namespace pdsm

#endif  // PDSM_CLIENT_MEASURE_GNUPLOT_H_
