// ThreadSanitizer build only (PDSM_SANITIZE=thread): Debian's Abseil is not built with TSan,
// so TSan cannot see absl::Mutex, CondVar or Notification order memory, and would report
// every field they guard as a race. Built as libpdsm_tsan_absl.so and LD_PRELOADed by
// scripts/sanitize.sh, it interposes the entry points our code uses (Abseil's own calls
// between them too), calls the real ones (dlsym RTLD_NEXT) and tells TSan what they do: a lock
// acquires, an unlock releases, a wait releases then acquires, Notify releases and a seen
// notification acquires. It adds happens-before edges only; it never hides a race between accesses
// that no lock orders.
#include <dlfcn.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>

#include "absl/synchronization/mutex.h"
#include "absl/synchronization/notification.h"
#include "absl/time/time.h"

// Weak: a process without the TSan runtime (a shell a test runs) loads this and never calls
// these.
extern "C" void __tsan_acquire(void* addr) __attribute__((weak));
extern "C" void __tsan_release(void* addr) __attribute__((weak));

namespace {

void Acquire(void* addr) {
  if (__tsan_acquire != nullptr) __tsan_acquire(addr);
}
void Release(void* addr) {
  if (__tsan_release != nullptr) __tsan_release(addr);
}

template <typename F>
F Real(const char* mangled) {
  void* f = dlsym(RTLD_NEXT, mangled);
  if (f == nullptr) {
    std::fprintf(stderr, "tsan_absl_annotations: %s not found\n", mangled);
    std::abort();
  }
  return reinterpret_cast<F>(f);
}

// The sync object of a Notification: its notified_yet_ flag, read inline by
// HasBeenNotified with an acquire load (absl 20220623: it follows the Mutex member).
void* NotifiedFlag(const absl::Notification* n) {
  return const_cast<char*>(reinterpret_cast<const char*>(n)) + sizeof(absl::Mutex);
}

// Abseil evaluates a condition with the lock held but inside its own code, after taking the
// lock again internally (sometimes on the thread that unlocks), and lets the lock go again
// internally when it is false: each evaluation acquires before and releases after, as a
// critical section of its own.
struct Guarded {
  absl::Mutex* mu;
  const absl::Condition* cond;
};
bool EvalGuarded(Guarded* g) {
  Acquire(g->mu);
  const bool met = g->cond->Eval();
  Release(g->mu);
  return met;
}

}  // namespace

namespace absl {
ABSL_NAMESPACE_BEGIN

#define PDSM_REAL(type, mangled) static const auto real = Real<type>(mangled)

void Mutex::Lock() {
  PDSM_REAL(void (*)(Mutex*), "_ZN4absl7debian35Mutex4LockEv");
  real(this);
  Acquire(this);
}
void Mutex::ReaderLock() {
  PDSM_REAL(void (*)(Mutex*), "_ZN4absl7debian35Mutex10ReaderLockEv");
  real(this);
  Acquire(this);
}
bool Mutex::TryLock() {
  PDSM_REAL(bool (*)(Mutex*), "_ZN4absl7debian35Mutex7TryLockEv");
  const bool locked = real(this);
  if (locked) Acquire(this);
  return locked;
}
void Mutex::Unlock() {
  PDSM_REAL(void (*)(Mutex*), "_ZN4absl7debian35Mutex6UnlockEv");
  Release(this);
  real(this);
}
void Mutex::ReaderUnlock() {
  PDSM_REAL(void (*)(Mutex*), "_ZN4absl7debian35Mutex12ReaderUnlockEv");
  Release(this);
  real(this);
}
void Mutex::LockWhen(const Condition& cond) {
  PDSM_REAL(void (*)(Mutex*, const Condition&),
            "_ZN4absl7debian35Mutex8LockWhenERKNS0_9ConditionE");
  Guarded g{this, &cond};
  real(this, Condition(&EvalGuarded, &g));
  Acquire(this);
}
void Mutex::Await(const Condition& cond) {
  PDSM_REAL(void (*)(Mutex*, const Condition&), "_ZN4absl7debian35Mutex5AwaitERKNS0_9ConditionE");
  Guarded g{this, &cond};
  Release(this);
  real(this, Condition(&EvalGuarded, &g));
  Acquire(this);
}
bool Mutex::AwaitWithTimeout(const Condition& cond, absl::Duration timeout) {
  PDSM_REAL(bool (*)(Mutex*, const Condition&, absl::Duration),
            "_ZN4absl7debian35Mutex16AwaitWithTimeoutERKNS0_9ConditionENS0_8DurationE");
  Guarded g{this, &cond};
  Release(this);
  const bool met = real(this, Condition(&EvalGuarded, &g), timeout);
  Acquire(this);
  return met;
}

bool Mutex::AwaitWithDeadline(const Condition& cond, absl::Time deadline) {
  PDSM_REAL(bool (*)(Mutex*, const Condition&, absl::Time),
            "_ZN4absl7debian35Mutex17AwaitWithDeadlineERKNS0_9ConditionENS0_4TimeE");
  Guarded g{this, &cond};
  Release(this);
  const bool met = real(this, Condition(&EvalGuarded, &g), deadline);
  Acquire(this);
  return met;
}

void CondVar::Wait(Mutex* mu) {
  PDSM_REAL(void (*)(CondVar*, Mutex*), "_ZN4absl7debian37CondVar4WaitEPNS0_5MutexE");
  Release(mu);
  real(this, mu);
  Acquire(mu);
}
bool CondVar::WaitWithTimeout(Mutex* mu, absl::Duration timeout) {
  PDSM_REAL(bool (*)(CondVar*, Mutex*, absl::Duration),
            "_ZN4absl7debian37CondVar15WaitWithTimeoutEPNS0_5MutexENS0_8DurationE");
  Release(mu);
  const bool timed_out = real(this, mu, timeout);
  Acquire(mu);
  return timed_out;
}

bool CondVar::WaitWithDeadline(Mutex* mu, absl::Time deadline) {
  PDSM_REAL(bool (*)(CondVar*, Mutex*, absl::Time),
            "_ZN4absl7debian37CondVar16WaitWithDeadlineEPNS0_5MutexENS0_4TimeE");
  Release(mu);
  const bool timed_out = real(this, mu, deadline);
  Acquire(mu);
  return timed_out;
}

void Notification::Notify() {
  PDSM_REAL(void (*)(Notification*), "_ZN4absl7debian312Notification6NotifyEv");
  Release(NotifiedFlag(this));
  real(this);
}
void Notification::WaitForNotification() const {
  PDSM_REAL(void (*)(const Notification*),
            "_ZNK4absl7debian312Notification19WaitForNotificationEv");
  real(this);
  Acquire(NotifiedFlag(this));
}
bool Notification::WaitForNotificationWithTimeout(absl::Duration timeout) const {
  PDSM_REAL(bool (*)(const Notification*, absl::Duration),
            "_ZNK4absl7debian312Notification30WaitForNotificationWithTimeoutENS0_8DurationE");
  const bool notified = real(this, timeout);
  if (notified) Acquire(NotifiedFlag(this));
  return notified;
}

ABSL_NAMESPACE_END
}  // namespace absl
