#include "core/pipeline/event_spill.h"

#include <cstring>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"

namespace pdsm {

int64_t TileEventsBytes(const TileEvents& events) {
  return static_cast<int64_t>(events.offsets.capacity() * sizeof(uint64_t) +
                              events.events.capacity() * sizeof(Event));
}

EventSpill::EventSpill(std::string dir, FileSystem* fs)
    : dir_(std::move(dir)), fs_(fs != nullptr ? fs : FileSystem::Default()) {}

absl::StatusOr<ScratchFile*> EventSpill::File() {
  absl::MutexLock lock(&mu_);
  if (!file_) {
    absl::StatusOr<std::unique_ptr<ScratchFile>> file = fs_->NewScratchFile(dir_);
    if (!file.ok()) return file.status();
    file_ = *std::move(file);
  }
  return file_.get();
}

absl::StatusOr<SpilledRun> EventSpill::Write(const TileEvents& events) {
  absl::StatusOr<ScratchFile*> file = File();
  if (!file.ok()) return file.status();
  SpilledRun run;
  run.pixels = events.PixelCount();
  run.events = events.events.size();
  std::vector<uint32_t> counts(run.pixels);
  for (size_t p = 0; p < run.pixels; ++p) {
    counts[p] = static_cast<uint32_t>(events.offsets[p + 1] - events.offsets[p]);
  }
  // Runs are laid end to end; the offset is reserved first, so writers never share bytes.
  run.offset = end_.fetch_add(run.bytes(), std::memory_order_relaxed);
  const absl::string_view count_bytes(reinterpret_cast<const char*>(counts.data()),
                                      counts.size() * sizeof(uint32_t));
  const absl::string_view event_bytes(reinterpret_cast<const char*>(events.events.data()),
                                      events.events.size() * sizeof(Event));
  if (absl::Status s = (*file)->WriteAt(run.offset, count_bytes); !s.ok()) return s;
  if (absl::Status s = (*file)->WriteAt(run.offset + count_bytes.size(), event_bytes); !s.ok()) {
    return s;
  }
  bytes_written_.fetch_add(static_cast<int64_t>(run.bytes()), std::memory_order_relaxed);
  return run;
}

absl::StatusOr<TileEvents> EventSpill::ReadAndRelease(const SpilledRun& run,
                                                      const TileEvents& shape) {
  if (run.pixels != shape.PixelCount()) {
    return absl::InternalError(absl::StrCat("a spilled run of ", run.pixels,
                                            " pixels read as tile ", shape.tile_index, " of ",
                                            shape.PixelCount()));
  }
  absl::StatusOr<ScratchFile*> file = File();
  if (!file.ok()) return file.status();
  TileEvents out;
  out.tile_index = shape.tile_index;
  out.x0 = shape.x0;
  out.y0 = shape.y0;
  out.width = shape.width;
  out.height = shape.height;
  std::vector<uint32_t> counts(run.pixels);
  if (absl::Status s = (*file)->ReadAt(run.offset, counts.size() * sizeof(uint32_t),
                                       reinterpret_cast<char*>(counts.data()));
      !s.ok()) {
    return s;
  }
  out.offsets.assign(run.pixels + 1, 0);
  for (size_t p = 0; p < run.pixels; ++p) out.offsets[p + 1] = out.offsets[p] + counts[p];
  if (out.offsets.back() != run.events) {
    return absl::DataLossError(absl::StrCat((*file)->label(), ": a run of tile ", shape.tile_index,
                                            " counts ", out.offsets.back(), " events where ",
                                            run.events, " were written"));
  }
  out.events.resize(run.events);
  if (absl::Status s =
          (*file)->ReadAt(run.offset + counts.size() * sizeof(uint32_t), run.events * sizeof(Event),
                          reinterpret_cast<char*>(out.events.data()));
      !s.ok()) {
    return s;
  }
  (*file)->Release(run.offset, run.bytes());
  return out;
}

}  // namespace pdsm
