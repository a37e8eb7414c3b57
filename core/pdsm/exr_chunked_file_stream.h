// OpenEXR's input stream over a single-part deep tiled file that exists only as a header and
// tiles' chunks kept elsewhere (tile_chunk.h), fetched one at a time as OpenEXR reads them:
// how PdsmWriter::WriteEncodedTiles hands OpenEXR's copyPixels tiles it never decodes.
//
// The file is virtual: the header and its offset table, then tile i's chunk at position
// header size + i * 2^32 (the offsets need no chunk's size in advance; a chunk is at most
// 4 GiB, as a deep tile's sizes allow). Not thread-safe.
#ifndef PDSM_CORE_PDSM_EXR_CHUNKED_FILE_STREAM_H_
#define PDSM_CORE_PDSM_EXR_CHUNKED_FILE_STREAM_H_

#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "absl/status/status.h"
#include "absl/status/statusor.h"

namespace pdsm {

class ExrChunkedFileStream final : public Imf::IStream {
 public:
  // Tile `index`'s chunk (row-major in the grid, coordinates set), or why not.
  using ChunkSource = std::function<absl::StatusOr<std::string>(int64_t index)>;

  // `header`: a deep tiled, one-level header of `tiles` tiles. `name` names the stream in
  // OpenEXR's messages. Errors: INTERNAL when OpenEXR cannot write the header.
  static absl::StatusOr<std::unique_ptr<ExrChunkedFileStream>> Create(const Imf::Header& header,
                                                                      int64_t tiles,
                                                                      ChunkSource source,
                                                                      const char* name);

  // Throws Iex::InputExc for bytes outside the header and the chunks (the source is asked only
  // for tiles in [0, tiles)), and when the source fails (error() then says why).
  bool read(char c[], int n) override;
  uint64_t tellg() override { return position_; }
  void seekg(uint64_t pos) override { position_ = pos; }

  // OK, or the source's first error.
  const absl::Status& error() const { return error_; }

 private:
  ExrChunkedFileStream(std::string prefix, int64_t tiles, ChunkSource source, const char* name);
  // Makes tile `index`'s chunk the one held, fetching it unless it is already.
  void Hold(int64_t index);

  std::string prefix_;  // the header and the offset table
  const int64_t tiles_;
  ChunkSource source_;
  uint64_t position_ = 0;
  int64_t held_index_ = -1;
  std::string held_;
  absl::Status error_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_EXR_CHUNKED_FILE_STREAM_H_
