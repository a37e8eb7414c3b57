#include "core/pdsm/pdsm_file.h"

#include <OpenEXR/ImfDeepFrameBuffer.h>
#include <OpenEXR/ImfDeepTiledInputFile.h>
#include <OpenEXR/ImfDeepTiledInputPart.h>
#include <OpenEXR/ImfDeepTiledOutputFile.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfPartType.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <map>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

#include "absl/strings/str_cat.h"
#include "absl/strings/str_format.h"
#include "absl/strings/string_view.h"
#include "core/pdsm/exr_file_scan.h"
#include "core/pdsm/exr_output_stream.h"
#include "core/pdsm/pdsm_exr_header.h"
#include "core/pdsm/pdsm_exr_tiles.h"
#include "core/util/atomic_file.h"
#include "core/util/file_system.h"

namespace pdsm {
namespace {

// ---------------------------------------------------------------------------------------
// Writer.

class ExrPdsmWriter final : public PdsmWriter {
 public:
  ExrPdsmWriter(std::string path, FileSystem* fs, const PdsmHeader& header,
                std::unique_ptr<AtomicFile> file, std::unique_ptr<ExrOutputStream> stream,
                std::unique_ptr<Imf::DeepTiledOutputFile> exr)
      : path_(std::move(path)),
        fs_(fs),
        header_(header),
        grid_{header.geometry.width, header.geometry.height, header.tile_size},
        file_(std::move(file)),
        stream_(std::move(stream)),
        exr_(std::move(exr)) {
    if (header_.adaptive()) header_.tile_samples.assign(grid_.Count(), 0);
  }

  ~ExrPdsmWriter() override {
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
      pending_.emplace(*index, tile);
      return absl::OkStatus();
    }
    if (absl::Status s = Emit(tile); !s.ok()) return s;
    for (auto it = pending_.find(next_tile_); it != pending_.end();
         it = pending_.find(next_tile_)) {
      if (absl::Status s = Emit(it->second); !s.ok()) return s;
      pending_.erase(it);
    }
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
    if (absl::Status s = file_->Commit(); !s.ok()) return Fail(s);
    finished_ = true;
    return absl::OkStatus();
  }

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
    if (index < next_tile_ || pending_.contains(index)) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) written twice", path_, tile.x0, tile.y0));
    }
    if (tile.offsets.size() != static_cast<size_t>(tile.width) * tile.height + 1) {
      return absl::InvalidArgumentError(
          absl::StrFormat("%s: tile (%d, %d) has %d offsets, expected %d", path_, tile.x0, tile.y0,
                          tile.offsets.size(), static_cast<size_t>(tile.width) * tile.height + 1));
    }
    if (absl::Status s = CheckTileFunctions(tile, path_); !s.ok()) return s;
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
        Imf::DeepTiledOutputFile copy(out, ExrHeaderFromPdsm(header_));
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
  PdsmHeader header_;  // tile_samples filled as tiles arrive (adaptive bakes)
  const TileGrid grid_;
  std::unique_ptr<AtomicFile> file_;         // the rewritten one once RewriteWithTileSamples() ran
  std::unique_ptr<ExrOutputStream> stream_;  // writes to *file_; null after a rewrite
  std::unique_ptr<Imf::DeepTiledOutputFile> exr_;  // writes to *stream_; null once finished
  std::map<int64_t, PdsmTile> pending_;            // out-of-order tiles by index
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
  absl::StatusOr<ExrHeaderBytes> scanned = ScanPdsmFile(
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
    for (uint64_t k = image.offsets[p]; k < image.offsets[p + 1]; ++k) {
      const float z = image.vertices[k].z;
      if (std::isnan(z) || (k > image.offsets[p] && z < image.vertices[k - 1].z)) {
        return absl::DataLossError(
            absl::StrFormat("%s: pixel (%d, %d): vertex depths are not nondecreasing (vertex %d)",
                            path, p % width, p / width, k - image.offsets[p]));
      }
    }
  }
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::unique_ptr<PdsmWriter>> PdsmWriter::Create(const std::string& path,
                                                               const PdsmHeader& header,
                                                               FileSystem* fs) {
  if (absl::Status s = ValidateHeaderForWrite(header, path); !s.ok()) return s;
  if (fs == nullptr) fs = FileSystem::Default();
  absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(path, fs);
  if (!file.ok()) return file.status();
  auto stream = std::make_unique<ExrOutputStream>(file->get());
  std::unique_ptr<Imf::DeepTiledOutputFile> exr;
  try {
    exr = std::make_unique<Imf::DeepTiledOutputFile>(*stream, ExrHeaderFromPdsm(header));
  } catch (...) {
    if (!stream->error().ok()) return stream->error();
    return absl::InternalError(
        StatusFromCurrentException((*file)->temp_path(), "cannot start").message());
  }
  return std::make_unique<ExrPdsmWriter>(path, fs, header, *std::move(file), std::move(stream),
                                         std::move(exr));
}

absl::StatusOr<PdsmHeader> ReadPdsmHeader(const std::string& path) {
  std::unique_ptr<Imf::MultiPartInputFile> file;
  if (absl::Status s = OpenChecked(path, &file); !s.ok()) return s;
  return PdsmHeaderFromExr(file->header(0), path);
}

absl::StatusOr<PdsmImage> ReadPdsm(const std::string& path) {
  std::unique_ptr<Imf::MultiPartInputFile> file;
  if (absl::Status s = OpenChecked(path, &file); !s.ok()) return s;
  PdsmImage image;
  absl::StatusOr<PdsmHeader> header = PdsmHeaderFromExr(file->header(0), path);
  if (!header.ok()) return header.status();
  image.header = *std::move(header);
  try {
    Imf::DeepTiledInputPart part(*file, 0);
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

}  // namespace pdsm
