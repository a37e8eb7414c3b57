#include "core/pdsm/exr_chunked_file_stream.h"

#include <Iex.h>
#include <OpenEXR/ImfDeepTiledOutputFile.h>

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>

#include "absl/strings/str_cat.h"
#include "core/pdsm/exr_memory_stream.h"
#include "core/pdsm/pdsm_exr_header.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

constexpr int kChunkStrideBits = 32;

}  // namespace

absl::StatusOr<std::unique_ptr<ExrChunkedFileStream>> ExrChunkedFileStream::Create(
    const Imf::Header& header, int64_t tiles, ChunkSource source, const char* name) {
  ExrStringOStream made(name);
  try {
    // A file of no tile yet: its header, then an offset table of zeros at its end.
    Imf::DeepTiledOutputFile empty(made, header, /*numThreads=*/0);
  } catch (...) {
    return absl::InternalError(StatusFromCurrentException(name, "cannot start").message());
  }
  std::string prefix = std::move(made.bytes());
  const uint64_t table_bytes = static_cast<uint64_t>(tiles) * sizeof(uint64_t);
  if (tiles < 0 || table_bytes > prefix.size()) {
    return absl::InternalError(
        absl::StrCat(name, ": the header is smaller than ", tiles, " tiles' offsets"));
  }
  ByteWriter table(prefix.data() + prefix.size() - table_bytes);
  for (int64_t i = 0; i < tiles; ++i) {
    table.U64(prefix.size() + (static_cast<uint64_t>(i) << kChunkStrideBits));
  }
  return std::unique_ptr<ExrChunkedFileStream>(
      new ExrChunkedFileStream(std::move(prefix), tiles, std::move(source), name));
}

ExrChunkedFileStream::ExrChunkedFileStream(std::string prefix, int64_t tiles, ChunkSource source,
                                           const char* name)
    : Imf::IStream(name), prefix_(std::move(prefix)), tiles_(tiles), source_(std::move(source)) {}

void ExrChunkedFileStream::Hold(int64_t index) {
  if (index == held_index_) return;
  if (index >= tiles_) {
    throw Iex::InputExc(absl::StrCat(fileName(), ": read past the last tile's chunk"));
  }
  held_index_ = -1;
  absl::StatusOr<std::string> chunk = source_(index);
  if (!chunk.ok()) {
    if (error_.ok()) error_ = chunk.status();
    throw Iex::InputExc(std::string(chunk.status().message()));
  }
  held_ = *std::move(chunk);
  held_index_ = index;
}

bool ExrChunkedFileStream::read(char c[], int n) {
  if (n < 0) throw Iex::InputExc(absl::StrCat(fileName(), ": read of ", n, " bytes"));
  size_t done = 0;
  const size_t wanted = static_cast<size_t>(n);
  while (done < wanted) {
    const uint64_t at = position_ + done;
    size_t count = 0;
    if (at < prefix_.size()) {
      count = std::min<size_t>(wanted - done, prefix_.size() - at);
      std::memcpy(c + done, prefix_.data() + at, count);
    } else {
      const uint64_t virtual_at = at - prefix_.size();
      Hold(static_cast<int64_t>(virtual_at >> kChunkStrideBits));
      const uint64_t within = virtual_at & ((uint64_t{1} << kChunkStrideBits) - 1);
      if (within >= held_.size()) {
        throw Iex::InputExc(absl::StrCat(fileName(), ": read past the end of tile ", held_index_,
                                         "'s chunk (", held_.size(), " bytes)"));
      }
      count = std::min<size_t>(wanted - done, held_.size() - within);
      std::memcpy(c + done, held_.data() + within, count);
    }
    done += count;
  }
  position_ += wanted;
  return true;
}

}  // namespace pdsm
