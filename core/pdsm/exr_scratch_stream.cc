#include "core/pdsm/exr_scratch_stream.h"

#include <Iex.h>

#include <algorithm>
#include <cstring>
#include <string>

#include "absl/status/status.h"
#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

constexpr size_t kBufferBytes = size_t{64} << 10;

}  // namespace

ExrScratchStream::ExrScratchStream(ScratchFile* file, uint64_t begin, uint64_t size)
    : Imf::IStream(file->label().c_str()), file_(file), begin_(begin), size_(size) {}

bool ExrScratchStream::read(char c[], int n) {
  if (n < 0 || position_ > size_ || static_cast<uint64_t>(n) > size_ - position_) {
    throw Iex::InputExc(absl::StrCat(file_->label(), ": a staged light ends at byte ", size_,
                                     " (read of ", n, " at ", position_, ")"));
  }
  const auto fetch = [this](uint64_t at, size_t count, char* out) {
    const absl::Status s = file_->ReadAt(begin_ + at, count, out);
    if (!s.ok()) throw Iex::IoExc(std::string(s.message()));
  };
  size_t done = 0;
  const size_t wanted = static_cast<size_t>(n);
  while (done < wanted) {
    const uint64_t at = position_ + done;
    if (at >= buffer_start_ && at < buffer_start_ + buffer_.size()) {
      const size_t from = static_cast<size_t>(at - buffer_start_);
      const size_t count = std::min(wanted - done, buffer_.size() - from);
      std::memcpy(c + done, buffer_.data() + from, count);
      done += count;
    } else if (wanted - done >= kBufferBytes) {  // large: straight into the caller's memory
      fetch(at, wanted - done, c + done);
      done = wanted;
    } else {
      buffer_.resize(static_cast<size_t>(std::min<uint64_t>(kBufferBytes, size_ - at)));
      buffer_start_ = at;
      fetch(at, buffer_.size(), buffer_.data());
    }
  }
  position_ += static_cast<uint64_t>(n);
  return position_ < size_;
}

}  // namespace pdsm
