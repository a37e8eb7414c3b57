// OpenEXR's output stream over an AtomicFile (core/util/atomic_file.h), so that the PDSM,
// written tile by tile and patched at the end (the tile offset table), streams through the
// project's one atomic-write path instead of a FILE* of its own.
#ifndef PDSM_CORE_PDSM_EXR_OUTPUT_STREAM_H_
#define PDSM_CORE_PDSM_EXR_OUTPUT_STREAM_H_

#include <OpenEXR/ImfIO.h>

#include <cstdint>

#include "absl/status/status.h"
#include "core/util/atomic_file.h"

namespace pdsm {

// Writes at a position of its own (seekp moves it, write advances it), through `file`, which
// it does not own and which must outlive it. Not thread-safe.
//
// Errors: write() throws Iex::IoExc, as OpenEXR expects, and the AtomicFile keeps the error
// (and drops its temporary file). OpenEXR swallows exceptions thrown while its destructor
// writes the tile offset table, so a writer asks error() after destroying the OpenEXR file:
// that is how a full disk at the very end is seen.
class ExrOutputStream final : public Imf::OStream {
 public:
  explicit ExrOutputStream(AtomicFile* file);

  void write(const char c[], int n) override;
  // Never fails: the position is ours, not the file's.
  uint64_t tellp() override { return position_; }
  void seekp(uint64_t pos) override { position_ = pos; }

  // OK, or the file's first error.
  const absl::Status& error() const { return file_->status(); }

 private:
  AtomicFile* const file_;
  uint64_t position_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_EXR_OUTPUT_STREAM_H_
