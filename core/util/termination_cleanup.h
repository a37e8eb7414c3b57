// What a process killed by SIGINT (Ctrl-C), SIGTERM or SIGHUP leaves behind: nothing of ours.
// Every AtomicFile (atomic_file.h) registers its temporary file here while it exists; a
// command-line binary calls RemoveTempFilesOnTerminationSignals() once at start, and then
// such a signal removes every registered temporary file before the process dies of the
// signal as it would have (same exit status for the shell). A SIGKILL cannot be caught:
// what it leaves is removed by the next writer in the same folder
// (FileSystem::RemoveStaleTempFiles, which AtomicFile runs once per folder).
//
// The registry is a fixed table of atomic slots, so the signal handler touches no lock and
// no allocator (async-signal-safe); a path that finds no free slot is simply not registered.
#ifndef PDSM_CORE_UTIL_TERMINATION_CLEANUP_H_
#define PDSM_CORE_UTIL_TERMINATION_CLEANUP_H_

#include <string>

namespace pdsm {

// Installs the handlers for SIGINT, SIGTERM and SIGHUP, except for a signal the process was
// started with ignored (nohup, background jobs of a script): that choice stays. Idempotent.
// Servers that wait for these signals themselves (pdsm-coordinator, pdsm-worker) do not call
// it: they block the signals and shut down cleanly instead.
void RemoveTempFilesOnTerminationSignals();

// Thread-safe. Registers `path` for removal on a termination signal; returns a handle for
// Unregister, or -1 when the table is full.
int RegisterTempFile(const std::string& path);
// Forgets a registration (handle -1: nothing). Call once the file is renamed or removed.
void UnregisterTempFile(int handle);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_TERMINATION_CLEANUP_H_
