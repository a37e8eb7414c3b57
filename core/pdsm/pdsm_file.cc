#include "core/pdsm/pdsm_file.h"

#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepTiledInputFile.h>
#include <OpenEXR/ImfDeepTiledInputPart.h>
#include <OpenEXR/ImfDeepTiledOutputFile.h>
#include <OpenEXR/ImfDeepTiledOutputPart.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfPartType.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <set>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/str_join.h"
#include "absl/strings/string_view.h"
#include "core/pdsm/exr_chunked_file_stream.h"
#include "core/pdsm/exr_file_scan.h"
#include "core/pdsm/exr_output_stream.h"
#include "core/pdsm/exr_scratch_stream.h"
#include "core/pdsm/pdsm_exr_header.h"
#include "core/pdsm/pdsm_exr_tiles.h"
#include "core/pdsm/pdsm_lights.h"
#include "core/pdsm/refined_pixel.h"
#include "core/pdsm/tile_chunk.h"
#include "core/pdsm/tile_reorder_buffer.h"
#include "core/util/atomic_file.h"
#include "core/util/file_system.h"

namespace pdsm {
namespace {

// ---------------------------------------------------------------------------------------
// Writer.

class ExrPdsmWriter final : public PdsmWriter {
 public:
  // `staged`: Finish() completes the file but does not commit it; it stays at staged_path()
  // until the writer is destroyed (a part of a multipart file, PdsmLightsWriter), whose
  // parts share `display_window` (unset: the data window).
  ExrPdsmWriter(std::string path, FileSystem* fs, const PdsmHeader& header,
                std::unique_ptr<AtomicFile> file, std::unique_ptr<ExrOutputStream> stream,
                std::unique_ptr<Imf::DeepTiledOutputFile> exr, bool staged,
                std::optional<Imath::Box2i> display_window, int64_t reorder_memory_bytes)
      : path_(std::move(path)),
        fs_(fs),
        staged_(staged),
        display_window_(display_window),
        header_(header),
        grid_{header.geometry.width, header.geometry.height, header.tile_size},
        file_(std::move(file)),
        stream_(std::move(stream)),
        exr_(std::move(exr)),
        pending_(ParentDir(path_), reorder_memory_bytes, fs) {
    if (header_.adaptive()) header_.tile_samples.assign(grid_.Count(), 0);
  }

  ~ExrPdsmWriter() override {
    // An unfinished file is given up first, so that OpenEXR's destructor, which writes the
    // offset table, writes nothing (the disk may be full: that is often why it is unfinished).
    if (!finished_ && file_) file_->Abandon();
    // In this order: OpenEXR writes through the stream, the stream through the file; the
    // file removes its temporary unless committed.
    exr_.reset();
    stream_.reset();
    file_.reset();
  }

  absl::Status WriteTile(const PdsmTile& tile) override {
    if (!error_.ok()) return error_;
    if (finished_) return absl::FailedPreconditionError(path_ + ": already finished");
    absl::StatusOr<int64_t> index = CheckTile(tile);
    if (!index.ok()) return index.status();
    if (header_.adaptive()) header_.tile_samples[*index] = tile.samples;
    if (*index != next_tile_) {
      // Out of order: keep it until the tiles before it are written, so that the file's
      // bytes do not depend on the order of arrival.
      if (absl::Status s = pending_.Put(*index, tile); !s.ok()) return Fail(s);
      return absl::OkStatus();
    }
    if (absl::Status s = Emit(tile); !s.ok()) return s;
    while (pending_.Contains(next_tile_)) {
      absl::StatusOr<std::optional<PdsmTile>> next = pending_.Take(next_tile_);
      if (!next.ok()) return Fail(next.status());
      if (absl::Status s = Emit(**next); !s.ok()) return s;
    }
    return absl::OkStatus();
  }

  absl::Status WriteEncodedTiles(const EncodedTileSource& source) override {
    if (!error_.ok()) return error_;
    if (finished_ || next_tile_ != 0 || pending_.size() != 0) {
      return absl::FailedPreconditionError(path_ + ": tiles were written already");
    }
    // The source's tiles, checked and moved to their place in the grid.
    const auto chunk_of = [&](int64_t index) -> absl::StatusOr<std::string> {
      absl::StatusOr<EncodedTile> tile = source(index);
      if (!tile.ok()) return tile.status();
      const int tx = static_cast<int>(index % grid_.TilesX());
      const int ty = static_cast<int>(index / grid_.TilesX());
      const int x0 = tx * grid_.tile_size, y0 = ty * grid_.tile_size;
      if (tile->x0 != x0 || tile->y0 != y0 || tile->width != grid_.TileWidth(x0) ||
          tile->height != grid_.TileHeight(y0) || tile->tile_size != grid_.tile_size ||
          tile->chunk.empty()) {
        return absl::InvalidArgumentError(absl::StrFormat(
            "%s: encoded tile %d is at (%d, %d) size %dx%d in tiles of %d with %d bytes, not the "
            "grid's cell (%d, %d) size %dx%d in tiles of %d",
            path_, index, tile->x0, tile->y0, tile->width, tile->height, tile->tile_size,
            tile->chunk.size(), x0, y0, grid_.TileWidth(x0), grid_.TileHeight(y0),
            grid_.tile_size));
      }
      if (header_.adaptive()) {
        if (tile->samples < 1 || tile->samples > header_.samples) {
          return absl::InvalidArgumentError(absl::StrFormat(
              "%s: tile (%d, %d) of an adaptive bake has %d samples, expected [1, %d]", path_, x0,
              y0, tile->samples, header_.samples));
        }
        header_.tile_samples[index] = tile->samples;
      }
      return RelocateTileChunk(std::move(tile->chunk), tx, ty);
    };
    absl::StatusOr<std::unique_ptr<ExrChunkedFileStream>> tiles = ExrChunkedFileStream::Create(
        ExrHeaderFromPdsm(header_, display_window_), grid_.Count(), chunk_of, path_.c_str());
    if (!tiles.ok()) return Fail(tiles.status());
    try {
      Imf::DeepTiledInputFile in(**tiles, /*numThreads=*/0);
      exr_->copyPixels(in);
    } catch (...) {
      if (!(*tiles)->error().ok()) return Fail((*tiles)->error());
      if (!stream_->error().ok()) return Fail(stream_->error());
      return Fail(absl::InternalError(absl::StrCat(
          StatusFromCurrentException(file_->temp_path(), "copying tiles into").message(), " (for ",
          path_, ")")));
    }
    next_tile_ = grid_.Count();
    return absl::OkStatus();
  }

  absl::Status Finish() override {
    if (!error_.ok()) return error_;
    if (finished_) return absl::FailedPreconditionError(path_ + ": already finished");
    if (next_tile_ != grid_.Count()) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "%s: %d of %d tiles missing", path_, grid_.Count() - next_tile_, grid_.Count()));
    }
    exr_.reset();  // writes the tile offset table; a failure shows in the file's status
    if (!file_->status().ok()) return Fail(file_->status());
    if (header_.adaptive()) {
      if (absl::Status s = RewriteWithTileSamples(); !s.ok()) return Fail(s);
    }
    if (staged_) {
      if (absl::Status s = file_->Flush(); !s.ok()) return Fail(s);
    } else if (absl::Status s = file_->Commit(); !s.ok()) {
      return Fail(s);
    }
    finished_ = true;
    return absl::OkStatus();
  }

  bool finished() const { return finished_; }
  // The header as written, adaptive tile counts included once finished.
  const PdsmHeader& header() const { return header_; }
  // Where a staged writer's finished file is. REQUIRES: staged, finished.
  const std::string& staged_path() const { return file_->temp_path(); }

 private:
  // The tile's index in row-major tile order, or why it is not a tile of the grid.
  absl::StatusOr<int64_t> CheckTile(const PdsmTile& tile) const {
    const int ts = grid_.tile_size;
    if (tile.x0 < 0 || tile.y0 < 0 || tile.x0 >= grid_.width || tile.y0 >= grid_.height ||
        tile.x0 % ts != 0 || tile.y0 % ts != 0 || tile.width != grid_.TileWidth(tile.x0) ||
        tile.height != grid_.TileHeight(tile.y0)) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: tile at (%d, %d) size %dx%d is not a cell of the %dx%d grid of %d-pixel tiles",
          path_, tile.x0, tile.y0, tile.width, tile.height, grid_.width, grid_.height, ts));
    }
    const int64_t index = (tile.y0 / ts) * grid_.TilesX() + tile.x0 / ts;
    if (index < next_tile_ || pending_.Contains(index)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) written twice", path_, tile.x0, tile.y0));
    }
    if (tile.offsets.size() != static_cast<size_t>(tile.width) * tile.height + 1) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) has %d offsets, expected %d", path_, tile.x0, tile.y0,
                          tile.offsets.size(), static_cast<size_t>(tile.width) * tile.height + 1));
    }
    if (absl::Status s = CheckTileFunctions(tile, path_, header_.max_refinement); !s.ok()) {
      return s;
    }
    if (header_.adaptive() && (tile.samples < 1 || tile.samples > header_.samples)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) of an adaptive bake has %d samples, expected [1, %d]",
                          path_, tile.x0, tile.y0, tile.samples, header_.samples));
    }
    return index;
  }

  // The header went out before any tile, but an adaptive bake knows its tiles' sample counts
  // only at the end: copy the finished tiles' compressed bytes (no decoding) into a second
  // file whose header carries them, and make that the one committed. The first one is
  // dropped (its temporary file removed) once the copy is whole.
  absl::Status RewriteWithTileSamples() {
    if (absl::Status s = file_->Flush(); !s.ok()) return s;
    absl::StatusOr<std::unique_ptr<AtomicFile>> copy_file = AtomicFile::Create(path_, fs_);
    if (!copy_file.ok()) return copy_file.status();
    {
      ExrOutputStream out(copy_file->get());
      try {
        Imf::DeepTiledInputFile in(file_->temp_path().c_str(), Imf::globalThreadCount());
        Imf::DeepTiledOutputFile copy(out, ExrHeaderFromPdsm(header_, display_window_));
        copy.copyPixels(in);
      } catch (...) {
        if (!out.error().ok()) return out.error();
        return StatusFromCurrentException((*copy_file)->temp_path(), "rewriting");
      }
    }
    // The copy's destructor wrote its offset table: a failure there shows only here.
    if (!(*copy_file)->status().ok()) return (*copy_file)->status();
    stream_.reset();
    file_ = *std::move(copy_file);
    return absl::OkStatus();
  }

  // Hands one tile to OpenEXR. REQUIRES: it is tile next_tile_.
  absl::Status Emit(const PdsmTile& tile) {
    const size_t pixels = static_cast<size_t>(tile.width) * tile.height;
    // OpenEXR only reads through these pointers when writing.
    Vertex* vertices = const_cast<Vertex*>(tile.vertices.data());
    buffers_.Resize(pixels);
    for (size_t p = 0; p < pixels; ++p) {
      buffers_.Set(p, vertices, tile.offsets[p], tile.offsets[p + 1]);
    }
    try {
      exr_->setFrameBuffer(buffers_.FrameBuffer(tile.width));
      exr_->writeTile(tile.x0 / grid_.tile_size, tile.y0 / grid_.tile_size);
    } catch (...) {
      if (!stream_->error().ok()) return Fail(stream_->error());
      return Fail(absl::InternalError(
          absl::StrCat(StatusFromCurrentException(file_->temp_path(), "writing").message(),
                       " (for ", path_, ")")));
    }
    ++next_tile_;
    return absl::OkStatus();
  }

  // Makes `status` sticky and drops the file at once: nothing of a failed writer stays on
  // disk while its owner still holds it.
  absl::Status Fail(absl::Status status) {
    error_ = status;
    exr_.reset();
    stream_.reset();
    file_.reset();
    return status;
  }

  const std::string path_;
  FileSystem* const fs_;
  const bool staged_;
  const std::optional<Imath::Box2i> display_window_;
  PdsmHeader header_;  // tile_samples filled as tiles arrive (adaptive bakes)
  const TileGrid grid_;
  std::unique_ptr<AtomicFile> file_;         // the rewritten one once RewriteWithTileSamples() ran
  std::unique_ptr<ExrOutputStream> stream_;  // writes to *file_; null after a rewrite
  std::unique_ptr<Imf::DeepTiledOutputFile> exr_;  // writes to *stream_; null once finished
  TileReorderBuffer pending_;                      // out-of-order tiles by index
  int64_t next_tile_ = 0;                          // all tiles before it are written
  DeepTileBuffers buffers_;
  absl::Status error_;  // sticky: after a failure nothing more is written
  bool finished_ = false;
};

// ---------------------------------------------------------------------------------------
// Reader.

// Opens the file for OpenEXR only after our own bounded read of its framing (exr_file_scan.h:
// no size in the file makes OpenEXR allocate more than the file can back) and of its header
// checksum (nothing read from a header that does not match it).
absl::Status OpenChecked(const std::string& path, std::unique_ptr<Imf::MultiPartInputFile>* file) {
  absl::StatusOr<std::vector<ExrHeaderBytes>> scanned = ScanPdsmFile(
      path, [&path](const ExrHeaderBytes& header) { return VerifyHeaderChecksum(header, path); });
  if (!scanned.ok()) return scanned.status();
  try {
    *file = std::make_unique<Imf::MultiPartInputFile>(path.c_str(), Imf::globalThreadCount(),
                                                      /*reconstructChunkOffsetTable=*/false);
  } catch (...) {
    return StatusFromCurrentException(path, "cannot read");
  }
  return absl::OkStatus();
}

// Sample counts of all pixels, into image->offsets as a prefix sum.
void ReadOffsets(Imf::DeepTiledInputPart& part, PdsmImage* image) {
  const PdsmGeometry& g = image->header.geometry;
  const size_t pixels = static_cast<size_t>(g.width) * g.height;
  std::vector<uint32_t> counts(pixels);
  Imf::DeepFrameBuffer fb;
  fb.insertSampleCountSlice(Imf::Slice(Imf::UINT, reinterpret_cast<char*>(counts.data()),
                                       sizeof(uint32_t), sizeof(uint32_t) * g.width));
  part.setFrameBuffer(fb);
  part.readPixelSampleCounts(0, part.numXTiles(0) - 1, 0, part.numYTiles(0) - 1);
  image->offsets.assign(pixels + 1, 0);
  for (size_t p = 0; p < pixels; ++p) image->offsets[p + 1] = image->offsets[p] + counts[p];
}

// Vertices of all tiles, straight into image->vertices.
void ReadVertices(Imf::DeepTiledInputPart& part, PdsmImage* image) {
  const PdsmGeometry& g = image->header.geometry;
  const TileGrid grid{g.width, g.height, image->header.tile_size};
  image->vertices.resize(image->offsets.back());
  DeepTileBuffers buffers;
  for (int ty = 0; ty < grid.TilesY(); ++ty) {
    for (int tx = 0; tx < grid.TilesX(); ++tx) {
      const int x0 = tx * grid.tile_size, y0 = ty * grid.tile_size;
      const int w = grid.TileWidth(x0), h = grid.TileHeight(y0);
      buffers.Resize(static_cast<size_t>(w) * h);
      for (int y = 0; y < h; ++y) {
        const size_t row = static_cast<size_t>(y0 + y) * g.width + x0;
        for (int x = 0; x < w; ++x) {
          buffers.Set(static_cast<size_t>(y) * w + x, image->vertices.data(),
                      image->offsets[row + x], image->offsets[row + x + 1]);
        }
      }
      part.setFrameBuffer(buffers.FrameBuffer(w));
      part.readTile(tx, ty);
    }
  }
}

absl::Status CheckDepthOrder(const PdsmImage& image, absl::string_view path) {
  const int width = image.header.geometry.width;
  const size_t pixels = image.offsets.size() - 1;
  for (size_t p = 0; p < pixels; ++p) {
    const std::string fault =
        PixelFunctionFault(std::span<const Vertex>(image.vertices.data() + image.offsets[p],
                                                   image.offsets[p + 1] - image.offsets[p]),
                           image.header.max_refinement);
    if (!fault.empty()) {
      return absl::DataLossError(
          absl::StrFormat("%s: pixel (%d, %d): %s", path, p % width, p / width, fault));
    }
  }
  return absl::OkStatus();
}

// ---------------------------------------------------------------------------------------
// Several lights.

// A writer of `header` into a new AtomicFile for `path`.
absl::StatusOr<std::unique_ptr<ExrPdsmWriter>> CreateExrWriter(
    const std::string& path, const PdsmHeader& header, FileSystem* fs, bool staged,
    const std::optional<Imath::Box2i>& display_window,
    int64_t reorder_memory_bytes = kTileReorderMemoryBytes) {
  if (absl::Status s = ValidateHeaderForWrite(header, path); !s.ok()) return s;
  if (fs == nullptr) fs = FileSystem::Default();
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path, fs);
  if (!file.ok()) return file.status();
  auto stream = std::make_unique<ExrOutputStream>(file->get());
  std::unique_ptr<Imf::DeepTiledOutputFile> exr;
  try {
    exr = std::make_unique<Imf::DeepTiledOutputFile>(*stream,
                                                     ExrHeaderFromPdsm(header, display_window));
  } catch (...) {
    if (!stream->error().ok()) return stream->error();
    return absl::InternalError(
        StatusFromCurrentException((*file)->temp_path(), "cannot start").message());
  }
  return std::make_unique<ExrPdsmWriter>(path, fs, header, *std::move(file), std::move(stream),
                                         std::move(exr), staged, display_window,
                                         reorder_memory_bytes);
}

// Each light into a staged single-part file (ExrPdsmWriter, staged), moved as soon as it is
// finished into one scratch file of all the lights (end to end, so that the writer holds a few
// descriptors however many lights there are), then every part's compressed tiles copied,
// undecoded, into one multipart file (OpenEXR's copyPixels).
class ExrPdsmLightsWriter final : public PdsmLightsWriter {
 public:
  ExrPdsmLightsWriter(std::string path, FileSystem* fs, int lights, Imath::Box2i display_window)
      : path_(std::move(path)), fs_(fs), lights_(lights), display_window_(display_window) {}

  absl::StatusOr<PdsmWriter*> BeginLight(const PdsmHeader& header) override {
    if (!error_.ok()) return error_;
    if (LightsBegun() == lights_) {
      return absl::FailedPreconditionError(
          absl::StrFormat("%s: all %d lights were begun already", path_, lights_));
    }
    if (current_ != nullptr && !current_->finished()) {
      return absl::FailedPreconditionError(
          absl::StrFormat("%s: light \"%s\" begun before light \"%s\" was finished", path_,
                          header.light_name, current_->header().light_name));
    }
    if (header.light_name.empty() || !names_.insert(header.light_name).second) {
      return absl::InvalidArgumentError(absl::StrFormat(
          "%s: every light of a multipart PDSM needs a name of its own (got \"%s\")", path_,
          header.light_name));
    }
    if (absl::Status s = StageCurrent(); !s.ok()) return Fail(s);
    absl::StatusOr<std::unique_ptr<ExrPdsmWriter>> part =
        CreateExrWriter(path_, header, fs_, /*staged=*/true, display_window_);
    if (!part.ok()) return Fail(part.status());
    current_ = *std::move(part);
    return current_.get();
  }

  absl::Status Finish() override {
    if (!error_.ok()) return error_;
    if (LightsBegun() != lights_ || !current_->finished()) {
      return absl::FailedPreconditionError(absl::StrFormat(
          "%s: %d of %d lights finished", path_,
          LightsBegun() - (current_ == nullptr || current_->finished() ? 0 : 1), lights_));
    }
    if (absl::Status s = StageCurrent(); !s.ok()) return Fail(s);
    absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path_, fs_);
    if (!file.ok()) return Fail(file.status());
    {
      ExrOutputStream out(file->get());
      try {
        std::vector<Imf::Header> headers;
        for (const StagedLight& light : staged_) {
          headers.push_back(ExrHeaderFromPdsm(light.header, display_window_));
        }
        Imf::MultiPartOutputFile multipart(out, headers.data(), static_cast<int>(headers.size()));
        std::vector<Imf::Header>().swap(headers);  // the file keeps its own copies
        for (size_t p = 0; p < staged_.size(); ++p) {
          ExrScratchStream staged(scratch_.get(), staged_[p].begin, staged_[p].size);
          Imf::DeepTiledInputFile in(staged, Imf::globalThreadCount());
          Imf::DeepTiledOutputPart(multipart, static_cast<int>(p)).copyPixels(in);
        }
      } catch (...) {
        if (!out.error().ok()) return Fail(out.error());
        return Fail(StatusFromCurrentException((*file)->temp_path(), "assembling"));
      }
    }
    // The multipart file's destructor wrote its offset tables: a failure shows only here.
    if (!(*file)->status().ok()) return Fail((*file)->status());
    if (absl::Status s = (*file)->Commit(); !s.ok()) return Fail(s);
    Drop();
    return absl::OkStatus();
  }

 private:
  // A finished light: its header as written and its single-part file's bytes in `scratch_`.
  struct StagedLight {
    PdsmHeader header;
    uint64_t begin = 0, size = 0;
  };

  int LightsBegun() const {
    return static_cast<int>(staged_.size()) + (current_ != nullptr ? 1 : 0);
  }

  // Moves the finished current light's file to the end of the scratch file (made at the
  // first light) and removes it. No-op without a current light.
  absl::Status StageCurrent() {
    if (current_ == nullptr) return absl::OkStatus();
    if (!scratch_) {
      absl::StatusOr<std::unique_ptr<ScratchFile>> scratch = fs_->NewScratchFile(ParentDir(path_));
      if (!scratch.ok()) return scratch.status();
      scratch_ = *std::move(scratch);
    }
    const std::string& staged_path = current_->staged_path();
    std::ifstream in(staged_path, std::ios::binary);
    StagedLight light{current_->header(), scratch_end_, 0};
    std::vector<char> buffer(size_t{1} << 20);
    while (in) {
      in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
      const size_t got = static_cast<size_t>(in.gcount());
      if (got == 0) break;
      if (absl::Status s = scratch_->WriteAt(scratch_end_, absl::string_view(buffer.data(), got));
          !s.ok()) {
        return s;
      }
      scratch_end_ += got;
      light.size += got;
    }
    if (in.bad() || !in.eof() || light.size == 0) {
      return absl::DataLossError(absl::StrCat(staged_path, ": cannot read back the light \"",
                                              light.header.light_name, "\" staged there"));
    }
    staged_.push_back(std::move(light));
    current_.reset();  // removes the staged file
    return absl::OkStatus();
  }

  // Removes whatever is staged.
  void Drop() {
    current_.reset();
    staged_.clear();
    scratch_.reset();
  }

  absl::Status Fail(absl::Status status) {
    error_ = status;
    Drop();
    return status;
  }

  const std::string path_;
  FileSystem* const fs_;
  const int lights_;
  const Imath::Box2i display_window_;
  std::unique_ptr<ExrPdsmWriter> current_;  // the light being written, in its own file
  std::vector<StagedLight> staged_;         // the lights before it
  std::unique_ptr<ScratchFile> scratch_;    // their files, end to end
  uint64_t scratch_end_ = 0;
  std::set<std::string> names_;
  absl::Status error_;
};

}  // namespace

absl::StatusOr<std::unique_ptr<PdsmWriter>> PdsmWriter::Create(const std::string& path,
                                                               const PdsmHeader& header,
                                                               FileSystem* fs,
                                                               int64_t reorder_memory_bytes) {
  absl::StatusOr<std::unique_ptr<ExrPdsmWriter>> writer =
      CreateExrWriter(path, header, fs, /*staged=*/false, std::nullopt, reorder_memory_bytes);
  if (!writer.ok()) return writer.status();
  return std::unique_ptr<PdsmWriter>(*std::move(writer));
}

absl::StatusOr<std::unique_ptr<PdsmLightsWriter>> PdsmLightsWriter::Create(
    const std::string& path, int lights, int max_width, int max_height, FileSystem* fs) {
  if (lights < 2 || max_width < 1 || max_height < 1) {
    return absl::InvalidArgumentError(absl::StrFormat(
        "%s: a multipart PDSM needs 2 or more lights and a size (got %d lights, %dx%d)", path,
        lights, max_width, max_height));
  }
  if (fs == nullptr) fs = FileSystem::Default();
  return std::make_unique<ExrPdsmLightsWriter>(
      path, fs, lights, Imath::Box2i(Imath::V2i(0, 0), Imath::V2i(max_width - 1, max_height - 1)));
}

namespace {

// The part of an open file that holds light `light` ("" for the file's only light).
absl::StatusOr<int> FindPart(const Imf::MultiPartInputFile& file, const std::string& path,
                             std::string_view light) {
  const int parts = file.parts();
  std::vector<std::string> names;
  for (int p = 0; p < parts; ++p) {
    const Imf::Header& h = file.header(p);
    names.push_back(h.hasName() ? h.name() : std::string());
    if (!light.empty() && names.back() == light) return p;
  }
  if (light.empty() && parts == 1) return 0;
  const std::string listed = absl::StrCat("\"", absl::StrJoin(names, "\", \""), "\"");
  if (light.empty()) {
    return absl::FailedPreconditionError(
        absl::StrFormat("%s holds %d lights (%s): name one (--light NAME)", path, parts, listed));
  }
  return absl::NotFoundError(
      absl::StrFormat("%s has no light \"%s\"; its lights: %s", path, light, listed));
}

absl::StatusOr<PdsmImage> ReadPart(Imf::MultiPartInputFile& file, const std::string& path,
                                   int part_index) {
  PdsmImage image;
  absl::StatusOr<PdsmHeader> header = PdsmHeaderFromExr(file.header(part_index), path);
  if (!header.ok()) return header.status();
  image.header = *std::move(header);
  try {
    Imf::DeepTiledInputPart part(file, part_index);
    if (!part.isComplete()) {
      return absl::DataLossError(absl::StrCat(path, ": incomplete file (truncated?)"));
    }
    ReadOffsets(part, &image);
    ReadVertices(part, &image);
  } catch (...) {
    return StatusFromCurrentException(path, "cannot read");
  }
  if (absl::Status s = CheckDepthOrder(image, path); !s.ok()) return s;
  return image;
}

}  // namespace

PdsmReader::PdsmReader(std::string path, std::unique_ptr<Imf::MultiPartInputFile> file,
                       std::vector<PdsmHeader> headers)
    : path_(std::move(path)),
      file_(std::move(file)),
      headers_(std::move(headers)),
      read_mu_(std::make_unique<absl::Mutex>()) {}
PdsmReader::PdsmReader(PdsmReader&&) noexcept = default;
PdsmReader& PdsmReader::operator=(PdsmReader&&) noexcept = default;
PdsmReader::~PdsmReader() = default;

absl::StatusOr<PdsmReader> PdsmReader::Open(const std::string& path) {
  std::unique_ptr<Imf::MultiPartInputFile> file;
  if (absl::Status s = OpenChecked(path, &file); !s.ok()) return s;
  std::vector<PdsmHeader> headers;
  for (int p = 0; p < file->parts(); ++p) {
    absl::StatusOr<PdsmHeader> header = PdsmHeaderFromExr(file->header(p), path);
    if (!header.ok()) return header.status();
    headers.push_back(*std::move(header));
  }
  return PdsmReader(path, std::move(file), std::move(headers));
}

absl::StatusOr<int> PdsmReader::FindLight(std::string_view light) const {
  return FindPart(*file_, path_, light);
}

absl::StatusOr<PdsmImage> PdsmReader::ReadLight(int part) {
  if (part < 0 || part >= static_cast<int>(headers_.size())) {
    return absl::OutOfRangeError(
        absl::StrFormat("%s: no part %d of %d", path_, part, headers_.size()));
  }
  return ReadPart(*file_, path_, part);
}

absl::StatusOr<PdsmTile> PdsmReader::ReadTile(int part, int tile_x, int tile_y) {
  if (part < 0 || part >= static_cast<int>(headers_.size())) {
    return absl::OutOfRangeError(
        absl::StrFormat("%s: no part %d of %d", path_, part, headers_.size()));
  }
  const PdsmHeader& header = headers_[part];
  const PdsmGeometry& g = header.geometry;
  const TileGrid grid{g.width, g.height, header.tile_size};
  if (tile_x < 0 || tile_x >= grid.TilesX() || tile_y < 0 || tile_y >= grid.TilesY()) {
    return absl::OutOfRangeError(absl::StrFormat("%s: no tile (%d, %d) in a grid of %dx%d", path_,
                                                 tile_x, tile_y, grid.TilesX(), grid.TilesY()));
  }
  PdsmTile tile;
  tile.x0 = tile_x * grid.tile_size;
  tile.y0 = tile_y * grid.tile_size;
  tile.width = grid.TileWidth(tile.x0);
  tile.height = grid.TileHeight(tile.y0);
  if (!header.tile_samples.empty()) {
    tile.samples = header.TileSamples(static_cast<size_t>(tile_y * grid.TilesX() + tile_x));
  }
  absl::MutexLock lock(read_mu_.get());
  try {
    Imf::DeepTiledInputPart exr_part(*file_, part);
    if (absl::Status s = ReadDeepTile(exr_part, tile_x, tile_y, path_, &tile); !s.ok()) return s;
  } catch (...) {
    return StatusFromCurrentException(path_, "cannot read");
  }
  if (absl::Status s = CheckTileFunctions(tile, path_, header.max_refinement); !s.ok()) {
    return absl::DataLossError(s.message());
  }
  return tile;
}

absl::StatusOr<std::vector<PdsmHeader>> ReadPdsmHeaders(const std::string& path) {
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
  if (!reader.ok()) return reader.status();
  return reader->headers();
}

absl::StatusOr<PdsmHeader> ReadPdsmHeader(const std::string& path, std::string_view light) {
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
  if (!reader.ok()) return reader.status();
  absl::StatusOr<int> part = reader->FindLight(light);
  if (!part.ok()) return part.status();
  return reader->headers()[*part];
}

absl::StatusOr<PdsmImage> ReadPdsm(const std::string& path, std::string_view light) {
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
  if (!reader.ok()) return reader.status();
  absl::StatusOr<int> part = reader->FindLight(light);
  if (!part.ok()) return part.status();
  return reader->ReadLight(*part);
}

absl::StatusOr<std::vector<PdsmImage>> ReadPdsmLights(const std::string& path,
                                                      std::string_view light) {
  absl::StatusOr<PdsmReader> reader = PdsmReader::Open(path);
  if (!reader.ok()) return reader.status();
  // The selected lights' parts, in file order (a sphere's are its six faces).
  absl::StatusOr<std::vector<PdsmLightParts>> selected =
      SelectLights(reader->headers(), path, light);
  if (!selected.ok()) return selected.status();
  std::vector<PdsmImage> lights;
  for (const PdsmLightParts& selected_light : *selected) {
    for (const int p : selected_light.parts) {
      absl::StatusOr<PdsmImage> image = reader->ReadLight(p);
      if (!image.ok()) return image.status();
      lights.push_back(*std::move(image));
    }
  }
  return lights;
}

}  // namespace pdsm
