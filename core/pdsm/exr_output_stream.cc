#include "core/pdsm/exr_output_stream.h"

#include <OpenEXR/IexBaseExc.h>

#include <cstddef>
#include <string>

namespace pdsm {

ExrOutputStream::ExrOutputStream(AtomicFile* file)
    : Imf::OStream(file->temp_path().c_str()), file_(file) {}

void ExrOutputStream::write(const char c[], int n) {
  if (n <= 0) return;
  absl::Status s = file_->WriteAt(position_, absl::string_view(c, static_cast<size_t>(n)));
  if (!s.ok()) throw Iex::IoExc(std::string(s.message()));
  position_ += static_cast<uint64_t>(n);
}

}  // namespace pdsm
