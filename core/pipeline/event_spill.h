// Where a bake's running event lists go when they outgrow its memory budget (issue #11,
// "memory flat in samples"). A tile's merged list holds a distinct depth for nearly every
// event of every sample in its penumbrae, so it grows with the samples; the engine
// (bake_engine.h) moves a group's lists here as runs once its budget is spent, and merges a
// tile's runs back when its stage completes. Merging is exact integer addition, so a tile
// merged from runs is the same, event for event, as one merged in memory: spilling changes no
// byte of the PDSM.
//
// A run is one tile's per-pixel lists in the process's own layout (never read by another
// machine or build): uint32 count per pixel, then the events (float z, int32 count).
// The scratch file (core/util/file_system.h) is created in `dir` at the first spill and has no
// name: nothing is left behind however the process ends. A run's blocks are released as soon
// as it is read back, so the file holds only the runs of stages still open.
#ifndef PDSM_CORE_PIPELINE_EVENT_SPILL_H_
#define PDSM_CORE_PIPELINE_EVENT_SPILL_H_

#include <atomic>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "absl/base/thread_annotations.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/events/event.h"
#include "core/util/file_system.h"

namespace pdsm {

// A tile's lists written out: where they are and how many of each.
struct SpilledRun {
  uint64_t offset = 0;
  uint64_t pixels = 0;
  uint64_t events = 0;
  uint64_t bytes() const { return pixels * sizeof(uint32_t) + events * sizeof(Event); }
};

// A tile's event lists in parts that cover its samples exactly once between them: lists in
// memory and runs in an EventSpill. A pixel's list is the merge of its parts' lists.
struct TileParts {
  std::vector<TileEvents> in_memory;
  std::vector<SpilledRun> spilled;
  TileEvents shape;  // the tile's index and rectangle, without lists
};

// The bytes a TileEvents holds in memory (its offsets and events), as the budget counts them.
int64_t TileEventsBytes(const TileEvents& events);

// Thread-safe: runs are written and read from any thread at once.
class EventSpill {
 public:
  // `fs` null means FileSystem::Default(). Nothing is created until the first Write.
  EventSpill(std::string dir, FileSystem* fs = nullptr);
  EventSpill(const EventSpill&) = delete;
  EventSpill& operator=(const EventSpill&) = delete;

  // Writes `events`' lists as a new run. Errors: the scratch file's (e.g. RESOURCE_EXHAUSTED
  // for a full disk), naming the folder.
  absl::StatusOr<SpilledRun> Write(const TileEvents& events);

  // Reads a run back as the lists of a tile shaped like `shape` (its index and rectangle;
  // its lists are ignored), then releases the run's blocks. REQUIRES: `run` came from Write
  // of a tile of that shape, and is read once. DATA_LOSS when the file does not hold it.
  absl::StatusOr<TileEvents> ReadAndRelease(const SpilledRun& run, const TileEvents& shape);

  // Reads `bytes` bytes of the scratch file at `offset` (a piece of a run). DATA_LOSS when the
  // file does not hold them.
  absl::Status Read(uint64_t offset, size_t bytes, void* out);
  // The run will not be read again: its blocks go back to the file system.
  void Release(const SpilledRun& run);

  // Bytes written since construction (every run, released or not).
  int64_t bytes_written() const { return bytes_written_.load(std::memory_order_relaxed); }

 private:
  absl::StatusOr<ScratchFile*> File();

  const std::string dir_;
  FileSystem* const fs_;
  absl::Mutex mu_;
  std::unique_ptr<ScratchFile> file_ ABSL_GUARDED_BY(mu_);
  std::atomic<uint64_t> end_{0};  // the next run's offset: runs are laid end to end
  std::atomic<int64_t> bytes_written_{0};
};

// Reads a run back in pixel order, a piece of at most kPieceEvents events at a time (a pixel
// with more is read whole), so that a tile merged from many runs holds only a piece of each.
// Not thread-safe. Errors do not stop the reading: Pixel then gives empty lists and status()
// says what went wrong, for the caller to check once at the end.
class SpilledRunReader {
 public:
  static constexpr size_t kPieceEvents = 8192;  // 64 KiB

  // Reads the run's per-pixel counts (4 bytes a pixel). `spill` must outlive the reader.
  SpilledRunReader(EventSpill* spill, const SpilledRun& run);

  // The list of pixel `p`, valid until the next call. REQUIRES: p < run.pixels, ascending
  // over calls.
  std::span<const Event> Pixel(size_t p);

  const absl::Status& status() const { return status_; }

 private:
  EventSpill* const spill_;
  const SpilledRun run_;
  std::vector<uint32_t> counts_;
  size_t next_pixel_ = 0;     // the first pixel whose start is not yet in next_event_
  uint64_t next_event_ = 0;   // index in the run of the first event of next_pixel_
  uint64_t piece_first_ = 0;  // index in the run of piece_[0]
  std::vector<Event> piece_;
  absl::Status status_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PIPELINE_EVENT_SPILL_H_
