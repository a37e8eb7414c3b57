#include "core/pipeline/event_spill.h"

#include <algorithm>
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
  // The run's layout is read in one place, SpilledRunReader, a piece at a time.
  SpilledRunReader reader(this, run);
  TileEvents out = TileShape(shape);
  out.offsets.reserve(run.pixels + 1);
  out.offsets.push_back(0);
  out.events.reserve(run.events);
  for (size_t p = 0; p < run.pixels; ++p) {
    const std::span<const Event> pixel = reader.Pixel(p);
    out.events.insert(out.events.end(), pixel.begin(), pixel.end());
    out.offsets.push_back(out.events.size());
  }
  if (!reader.status().ok()) return reader.status();
  if (out.events.size() != run.events) {
    return absl::DataLossError(absl::StrCat("a spilled run of tile ", shape.tile_index, " holds ",
                                            out.events.size(), " events where ", run.events,
                                            " were written"));
  }
  Release(run);
  return out;
}

absl::Status EventSpill::Read(uint64_t offset, size_t bytes, void* out) {
  absl::StatusOr<ScratchFile*> file = File();
  if (!file.ok()) return file.status();
  return (*file)->ReadAt(offset, bytes, static_cast<char*>(out));
}

void EventSpill::Release(const SpilledRun& run) {
  absl::StatusOr<ScratchFile*> file = File();
  if (file.ok()) (*file)->Release(run.offset, run.bytes());
}

SpilledRunReader::SpilledRunReader(EventSpill* spill, const SpilledRun& run)
    : spill_(spill), run_(run), counts_(run.pixels) {
  status_ = spill_->Read(run_.offset, counts_.size() * sizeof(uint32_t), counts_.data());
}

std::span<const Event> SpilledRunReader::Pixel(size_t p) {
  if (!status_.ok() || p >= counts_.size()) return {};
  for (; next_pixel_ < p; ++next_pixel_) next_event_ += counts_[next_pixel_];
  const uint64_t first = next_event_;
  const uint64_t count = counts_[p];
  if (count == 0) return {};
  if (first + count > run_.events) {
    status_ = absl::DataLossError(
        absl::StrCat("a spilled run counts more events than the ", run_.events, " it holds"));
    return {};
  }
  if (first < piece_first_ || first + count > piece_first_ + piece_.size()) {
    // The next piece starts at this pixel and holds it whole.
    const uint64_t size =
        std::min<uint64_t>(std::max<uint64_t>(count, kPieceEvents), run_.events - first);
    piece_.resize(size);
    piece_first_ = first;
    status_ = spill_->Read(run_.offset + run_.pixels * sizeof(uint32_t) + first * sizeof(Event),
                           size * sizeof(Event), piece_.data());
    if (!status_.ok()) return {};
  }
  return {piece_.data() + (first - piece_first_), count};
}

}  // namespace pdsm
