// Which jobs' plans the coordinator holds in memory, within --max-planned-mib. A job holds its
// plans (per light: sample positions, a surfaces-only bake's receivers, a bit per tile) and
// the engine's few words per tile group from its activation to its end (JobHeldBytes). A job whose
// plans do not fit beside those held waits QUEUED without them (it was planned at submit, so its
// errors are the submit's, then they were dropped) and is planned again when it is its turn and its
// bytes fit. Turns go in scheduling order (priority, then submission), and a waiting job is never
// passed over: a large job is not starved by a stream of small ones. A job alone always fits (when
// nothing is held), so a limit lowered across a restart cannot stall the queue. A running job's
// refinement levels add what they hold as they start and end (Grow).
//
// Bookkeeping only: the coordinator plans, activates, cancels and ends jobs, and tells this
// what happened. Thread-safe.
#ifndef PDSM_SERVER_PLAN_BUDGET_H_
#define PDSM_SERVER_PLAN_BUDGET_H_

#include <cstdint>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>

#include "absl/base/thread_annotations.h"
#include "absl/synchronization/mutex.h"

namespace pdsm {

class PlanBudget {
 public:
  struct Entry {
    std::string job_id;
    int priority = 0;
    int64_t sequence = 0;  // submission order
    int64_t bytes = 0;     // its plans' bytes (JobHeldBytes); < 0 while unknown (not planned)
  };

  explicit PlanBudget(int64_t limit_bytes);

  // A job just planned for its submit: true when it activates now (nothing waits ahead of it
  // and its bytes fit, or nothing is held), its bytes counted (then Activated, or Release if
  // activating fails); false when it waits (drop its plans).
  bool Admit(const Entry& job);
  // A job to be planned when it is its turn (a resumed one): it waits in order.
  void Enqueue(const Entry& job);
  // The first waiting job when its bytes (as last planned; 0 when unknown) fit beside those
  // held, or nothing is held: it leaves the queue and counts as activating. Then Planned.
  std::optional<Entry> TakeNext();

  enum class Verdict {
    kActivate,   // its bytes are counted: activate it, then Activated
    kWait,       // they do not fit beside those held: it is first in the queue again, with
                 // them; drop the plans
    kCancelled,  // a cancel came while it was being planned: it is gone from here; record it
  };
  // An activating job from TakeNext has been planned again: `bytes` as they are now.
  Verdict Planned(const std::string& job_id, int64_t bytes);
  // The job's engine jobs are added. True when a cancel came while it was activating: the
  // caller cancels it now.
  bool Activated(const std::string& job_id);
  // A running job holds `bytes` more than it was admitted with: a light's refinement level,
  // whose size is known only once its base map is baked (its plan when it starts, its
  // spliced tiles when it ends). Never refused and never stops the job, whose base map is
  // done; the held bytes may then pass the limit, and waiting jobs wait until they fit again.
  // Released with the rest. Nothing for a job that holds nothing here.
  void Grow(const std::string& job_id, int64_t bytes);
  // The job holds nothing any more (it ended, or could not be activated); a waiting job leaves
  // the queue. Nothing for a job this does not know.
  void Release(const std::string& job_id);

  enum class CancelOutcome {
    kNotHere,     // neither waiting nor activating: running or gone
    kWasWaiting,  // it left the queue: the caller records it cancelled
    kActivating,  // it will be cancelled by whoever activates it (Planned or Activated)
  };
  CancelOutcome Cancel(const std::string& job_id);

  bool HasWaiting() const;
  // Why the job waits, for people ("" when it does not).
  std::string WaitingReason(const std::string& job_id) const;

  struct Usage {
    int64_t held_bytes = 0;
    int64_t limit_bytes = 0;
    int jobs_held = 0;
    int jobs_waiting = 0;
  };
  Usage usage() const;

 private:
  struct Held {
    Entry entry;        // as admitted or taken (its place in the queue, should it wait again)
    int64_t bytes = 0;  // counted in held_bytes_
    bool activating = false;
    bool cancel_requested = false;
  };
  // Scheduling order: priority descending, then sequence, then id.
  using WaitKey = std::tuple<int, int64_t, std::string>;
  static WaitKey KeyOf(const Entry& job) { return {-job.priority, job.sequence, job.job_id}; }
  bool Fits(int64_t bytes) const ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);
  void Wait(const Entry& job) ABSL_EXCLUSIVE_LOCKS_REQUIRED(mu_);

  const int64_t limit_bytes_;
  mutable absl::Mutex mu_;
  std::map<std::string, Held> held_ ABSL_GUARDED_BY(mu_);
  int64_t held_bytes_ ABSL_GUARDED_BY(mu_) = 0;
  std::map<WaitKey, Entry> waiting_ ABSL_GUARDED_BY(mu_);
  std::map<std::string, WaitKey> waiting_keys_ ABSL_GUARDED_BY(mu_);  // job id -> its key
};

}  // namespace pdsm

#endif  // PDSM_SERVER_PLAN_BUDGET_H_
