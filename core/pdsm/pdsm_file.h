// The PDSM file: an OpenEXR deep tiled image, one deep sample per function vertex, with a
// depth channel "Z" and an attenuation channel "attenuation" (FLOAT both), plus header
// attributes for everything PdsmHeader holds. Byte layout: docs/pdsm_format.md.
#ifndef PDSM_CORE_PDSM_PDSM_FILE_H_
#define PDSM_CORE_PDSM_PDSM_FILE_H_

#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "core/pdsm/pdsm_image.h"
#include "core/util/file_system.h"

namespace pdsm {

// Writes a PDSM tile by tile. The file streams through an AtomicFile (core/util/atomic_file.h):
// written to "<path>.tmp-XXXXXX" in the same folder, synced and renamed onto `path` by
// Finish(), so a failed or abandoned bake leaves `path` as it was and no temporary file (the
// first error removes it, so does the destructor unless Finish() succeeded). After an error
// every call returns it again. I/O errors are the FileSystem's (RESOURCE_EXHAUSTED for a full
// disk, NOT_FOUND for a missing folder, …) and name the file.
// Tiles are those of the grid of header.tile_size; they may be added in any order, and the
// bytes of the file do not depend on that order. Not thread-safe.
class PdsmWriter {
 public:
  // `fs` null means FileSystem::Default(); it must outlive the writer.
  static absl::StatusOr<std::unique_ptr<PdsmWriter>> Create(const std::string& path,
                                                            const PdsmHeader& header,
                                                            FileSystem* fs = nullptr);
  virtual ~PdsmWriter() = default;

  // REQUIRES: tile is one cell of the tile grid, given once.
  virtual absl::Status WriteTile(const PdsmTile& tile) = 0;
  // REQUIRES: every tile written. Commits the file (AtomicFile::Commit: sync, rename, sync
  // the folder).
  virtual absl::Status Finish() = 0;
};

// Reads a whole PDSM. Errors: NOT_FOUND (no file), DATA_LOSS (not a PDSM or corrupt),
// FAILED_PRECONDITION (a format version this build does not read).
absl::StatusOr<PdsmImage> ReadPdsm(const std::string& path);

// Reads only the header.
absl::StatusOr<PdsmHeader> ReadPdsmHeader(const std::string& path);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_FILE_H_
