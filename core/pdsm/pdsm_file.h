// The PDSM file: an OpenEXR deep tiled image, one deep sample per function vertex, with a
// depth channel "Z" and an attenuation channel "attenuation" (FLOAT both), plus header
// attributes for everything PdsmHeader holds. Byte layout: docs/pdsm_format.md.
#ifndef PDSM_CORE_PDSM_PDSM_FILE_H_
#define PDSM_CORE_PDSM_PDSM_FILE_H_

#include <OpenEXR/ImfForward.h>  // Imf::MultiPartInputFile, held by PdsmReader

#include <functional>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "absl/status/status.h"
#include "absl/status/statusor.h"
#include "absl/synchronization/mutex.h"
#include "core/pdsm/pdsm_image.h"
#include "core/pdsm/tile_chunk.h"
#include "core/pdsm/tile_reorder_buffer.h"
#include "core/util/file_system.h"

namespace pdsm {

// Writes a PDSM tile by tile. The file streams through an AtomicFile (core/util/atomic_file.h):
// written to "<path>.tmp-XXXXXX" in the same folder, synced and renamed onto `path` by
// Finish(), so a failed or abandoned bake leaves `path` as it was and no temporary file (the
// first error removes it, so does the destructor unless Finish() succeeded). After an error
// every call returns it again. I/O errors are the FileSystem's (RESOURCE_EXHAUSTED for a full
// disk, NOT_FOUND for a missing folder, …) and name the file.
// Tiles are those of the grid of header.tile_size; they may be added in any order, and the
// bytes of the file do not depend on that order: a tile that comes before its turn waits in a
// TileReorderBuffer (tile_reorder_buffer.h), in memory up to `reorder_memory_bytes` and in a
// scratch file beside `path` past that, so the writer's memory does not grow with the map.
// Not thread-safe.
class PdsmWriter {
 public:
  // `fs` null means FileSystem::Default(); it must outlive the writer.
  static absl::StatusOr<std::unique_ptr<PdsmWriter>> Create(
      const std::string& path, const PdsmHeader& header, FileSystem* fs = nullptr,
      int64_t reorder_memory_bytes = kTileReorderMemoryBytes);
  virtual ~PdsmWriter() = default;

  // REQUIRES: tile is one cell of the tile grid, given once.
  virtual absl::Status WriteTile(const PdsmTile& tile) = 0;
  // Writes every tile at once from tiles encoded where they were finished
  // (core/pdsm/tile_chunk.h), copied into the file without being decoded or compressed again:
  // `source(index)` gives the tile of row-major index `index` of the grid, each once, in
  // ascending order. The file's bytes are those WriteTile would write for the same tiles.
  // REQUIRES: no tile written yet. Errors: the source's (the first, returned as it is),
  // INVALID_ARGUMENT for a tile that is not the grid's cell `index` (or, in an adaptive bake,
  // has samples outside [1, header.samples]), and the writer's own.
  using EncodedTileSource = std::function<absl::StatusOr<EncodedTile>(int64_t index)>;
  virtual absl::Status WriteEncodedTiles(const EncodedTileSource& source) = 0;
  // REQUIRES: every tile written. Commits the file (AtomicFile::Commit: sync, rename, sync
  // the folder).
  virtual absl::Status Finish() = 0;
};

// Writes the PDSM of a scene with several lights: one multipart deep OpenEXR file, one part
// per light in the order begun, each part what PdsmWriter writes for that light alone plus
// the light's name (docs/pdsm_format.md, "Several lights"). Lights are written one after
// another: each goes to a temporary file beside `path` (as PdsmWriter's), moved once finished
// to the end of one unnamed scratch file beside `path` (core/util/file_system.h: gone however
// the process ends), so that the writer holds a few descriptors whatever the number of
// lights; Finish() copies every part's compressed tiles, undecoded, into the file, committed
// as PdsmWriter commits. The bytes depend only on the headers and tiles, not on the order of
// tiles within a light. Errors as PdsmWriter's (and the scratch file's), sticky. Not
// thread-safe.
class PdsmLightsWriter {
 public:
  // `lights` >= 2 parts; every part's resolution at most max_width x max_height (the file's
  // display window, which OpenEXR requires to be one for all parts). `fs` null: the real one.
  static absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> Create(const std::string& path,
                                                                  int lights, int max_width,
                                                                  int max_height,
                                                                  FileSystem* fs = nullptr);
  virtual ~PdsmLightsWriter() = default;

  // The writer of the next light's part, owned by this (valid until the next BeginLight,
  // Finish or destruction): its WriteTile and Finish as PdsmWriter's, except that Finish
  // completes the part only.
  // REQUIRES: the light before it finished. INVALID_ARGUMENT when header.light_name is empty
  // or names a light begun already.
  virtual absl::StatusOr<PdsmWriter*> BeginLight(const PdsmHeader& header) = 0;
  // REQUIRES: every light finished. Assembles and commits the file.
  virtual absl::Status Finish() = 0;
};

// An open PDSM file: its framing checked and its headers read once (the bounded pre-read and
// the checksums of ReadPdsm), each light's functions read when asked. For a consumer of
// several lights of one file, which would otherwise scan the file once per light. Not
// thread-safe; movable.
class PdsmReader {
 public:
  // Errors as ReadPdsm's.
  static absl::StatusOr<PdsmReader> Open(const std::string& path);
  PdsmReader(PdsmReader&&) noexcept;
  PdsmReader& operator=(PdsmReader&&) noexcept;
  ~PdsmReader();

  const std::string& path() const { return path_; }
  // One per light (part), in file order.
  const std::vector<PdsmHeader>& headers() const { return headers_; }
  int light_count() const { return static_cast<int>(headers_.size()); }
  // The part of light `light` as ReadPdsm selects it (empty: the only light), with its errors.
  absl::StatusOr<int> FindLight(std::string_view light) const;
  // The whole PDSM of part `part`. OUT_OF_RANGE for no such part; else errors as ReadPdsm's.
  absl::StatusOr<PdsmImage> ReadLight(int part);

  // One tile of part `part`: tile (tile_x, tile_y) of its grid (header.tile_size pixels a
  // side, the last row and column clipped), read alone: what a reader that cannot hold the
  // whole map uses (core/pdsm/pdsm_tile_cache.h). `samples` as PdsmTile's (0: the header's).
  // OUT_OF_RANGE for no such part or tile; DATA_LOSS for a corrupt tile (depths not nondecreasing,
  // counts past a tile's size). Thread-safe: concurrent calls are serialized.
  absl::StatusOr<PdsmTile> ReadTile(int part, int tile_x, int tile_y);

 private:
  PdsmReader(std::string path, std::unique_ptr<Imf::MultiPartInputFile> file,
             std::vector<PdsmHeader> headers);

  std::string path_;
  std::unique_ptr<Imf::MultiPartInputFile> file_;
  std::vector<PdsmHeader> headers_;
  std::unique_ptr<absl::Mutex> read_mu_;  // a part's frame buffer and read go together
};

// Reads one light's whole PDSM. `light` empty: the file's only light (FAILED_PRECONDITION
// naming the lights when it holds several); else the part named `light` (NOT_FOUND naming the
// lights there are when none is). Errors: NOT_FOUND (no file), DATA_LOSS (not a PDSM or
// corrupt), FAILED_PRECONDITION (a format version this build does not read).
absl::StatusOr<PdsmImage> ReadPdsm(const std::string& path, std::string_view light = {});

// Every part of the file, in file order (one for a one-light file); only the parts of the light
// named `light` when it is not empty (a sphere's six faces, or one face by its own name:
// core/pdsm/pdsm_lights.h). Errors as ReadPdsm's; NOT_FOUND names the file's lights.
absl::StatusOr<std::vector<PdsmImage>> ReadPdsmLights(const std::string& path,
                                                      std::string_view light = {});

// Only the header of `light`, as ReadPdsm selects it.
absl::StatusOr<PdsmHeader> ReadPdsmHeader(const std::string& path, std::string_view light = {});

// Every light's header, in file order. Errors as ReadPdsm's.
absl::StatusOr<std::vector<PdsmHeader>> ReadPdsmHeaders(const std::string& path);

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_PDSM_FILE_H_
