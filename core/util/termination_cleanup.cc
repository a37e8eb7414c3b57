#include "core/util/termination_cleanup.h"

#include <signal.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <mutex>

namespace pdsm {
namespace {

// Writers in flight at once: a bake writes one PDSM and one or two previews; the coordinator,
// which does not install the handlers, may hold more than this and simply registers fewer.
constexpr int kSlots = 256;

// Each slot owns the malloc'ed copy of a path while it is non-null. Whoever exchanges a
// non-null pointer out of a slot owns it: Unregister frees it; the handler, which exchanges
// too, only unlinks it (the process is about to die).
std::atomic<char*> slots[kSlots];

constexpr int kSignals[] = {SIGINT, SIGTERM, SIGHUP};

void RemoveRegisteredAndDie(int signal_number) {
  const int saved_errno = errno;
  for (std::atomic<char*>& slot : slots) {
    if (char* path = slot.exchange(nullptr)) ::unlink(path);
  }
  errno = saved_errno;
  // SA_RESETHAND restored the default action, and the signal is blocked while its handler
  // runs: it is delivered again as this handler returns, and the process dies of it.
  ::raise(signal_number);
}

}  // namespace

void RemoveTempFilesOnTerminationSignals() {
  static std::once_flag once;
  std::call_once(once, [] {
    for (const int signal_number : kSignals) {
      struct sigaction current;
      if (::sigaction(signal_number, nullptr, &current) != 0) continue;
      if (current.sa_handler == SIG_IGN) continue;
      struct sigaction action;
      std::memset(&action, 0, sizeof(action));
      action.sa_handler = RemoveRegisteredAndDie;
      sigemptyset(&action.sa_mask);
      action.sa_flags = SA_RESETHAND;
      ::sigaction(signal_number, &action, nullptr);
    }
  });
}

int RegisterTempFile(const std::string& path) {
  char* copy = ::strdup(path.c_str());
  if (copy == nullptr) return -1;
  for (int i = 0; i < kSlots; ++i) {
    char* expected = nullptr;
    if (slots[i].compare_exchange_strong(expected, copy)) return i;
  }
  std::free(copy);
  return -1;
}

void UnregisterTempFile(int handle) {
  if (handle < 0 || handle >= kSlots) return;
  std::free(slots[handle].exchange(nullptr));
}

}  // namespace pdsm
