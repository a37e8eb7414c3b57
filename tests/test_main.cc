// The main of every GoogleTest binary of pdsm: GoogleTest's own, plus a stack trace on a crash.
//
// ctest runs each test in a process of its own and, when one dies of a signal, says only
// "Subprocess aborted" or "SEGFAULT". A flake seen once on a CI machine must be diagnosable
// from that one log, so a fatal signal (SIGABRT from a failed check or std::terminate,
// SIGSEGV, SIGBUS, SIGFPE, SIGILL) prints the failing thread's symbolized stack to stderr
// before the process dies as it would have (absl's failure signal handler re-raises).
#include <gtest/gtest.h>

#include "absl/debugging/failure_signal_handler.h"
#include "absl/debugging/symbolize.h"

int main(int argc, char** argv) {
  absl::InitializeSymbolizer(argv[0]);
  absl::InstallFailureSignalHandler(absl::FailureSignalHandlerOptions{});
  testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
