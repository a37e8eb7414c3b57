#include "core/pdsm/exr_memory_stream.h"

#include <Iex.h>

#include <cstring>

#include "absl/strings/str_cat.h"

namespace pdsm {

void ExrStringOStream::write(const char c[], int n) {
  const size_t end = static_cast<size_t>(position_) + static_cast<size_t>(n);
  if (end > bytes_.size()) bytes_.resize(end);
  std::memcpy(bytes_.data() + position_, c, static_cast<size_t>(n));
  position_ = end;
}

bool ExrStringIStream::read(char c[], int n) {
  if (n < 0 || position_ > bytes_.size() || static_cast<uint64_t>(n) > bytes_.size() - position_) {
    throw Iex::InputExc(absl::StrCat(fileName(), ": read of ", n, " bytes at ", position_,
                                     " past the end (", bytes_.size(), " bytes)"));
  }
  std::memcpy(c, bytes_.data() + position_, static_cast<size_t>(n));
  position_ += static_cast<uint64_t>(n);
  return position_ < bytes_.size();
}

}  // namespace pdsm
