// OpenEXR's input stream over a byte range of a scratch file (core/util/file_system.h): how a
// multipart PDSM writer reads back the lights it staged, end to end, in one unnamed file
// (pdsm_file.h, PdsmLightsWriter), instead of one open file per light.
#ifndef PDSM_CORE_PDSM_EXR_SCRATCH_STREAM_H_
#define PDSM_CORE_PDSM_EXR_SCRATCH_STREAM_H_

#include <OpenEXR/ImfIO.h>

#include <cstdint>
#include <vector>

#include "core/util/file_system.h"

namespace pdsm {

// Reads bytes [begin, begin + size) of `file`, which it does not own and which must outlive
// it, as if they were a whole file (position 0 is `begin`), through a 64 KiB buffer (OpenEXR
// reads a header a few bytes at a time: one system call each cost more than the tiles' copy
// in a file of 10,000 lights). Not thread-safe.
//
// Errors: read() throws Iex::InputExc past the range's end, as OpenEXR expects of a file, and
// Iex::IoExc when the scratch file cannot be read (its message names it).
class ExrScratchStream final : public Imf::IStream {
 public:
  ExrScratchStream(ScratchFile* file, uint64_t begin, uint64_t size);

  // True while bytes remain after the n read.
  bool read(char c[], int n) override;
  uint64_t tellg() override { return position_; }
  void seekg(uint64_t pos) override { position_ = pos; }

 private:
  ScratchFile* const file_;
  const uint64_t begin_;
  const uint64_t size_;
  uint64_t position_ = 0;
  std::vector<char> buffer_;  // bytes [buffer_start_, buffer_start_ + buffer_.size())
  uint64_t buffer_start_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_EXR_SCRATCH_STREAM_H_
