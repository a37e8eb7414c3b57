#include "core/pipeline/result_digest.h"

#include "core/assets/mesh_asset.h"
#include "core/util/little_endian.h"

namespace pdsm {
namespace {

// Feeds the hash in buffers of this many bytes, so that a result of millions of events costs
// no copy of its size.
constexpr size_t kChunkBytes = size_t{1} << 16;

class DigestWriter {
 public:
  explicit DigestWriter(Sha256* hash) : hash_(hash) {}
  ~DigestWriter() { Flush(); }

  void U64(uint64_t v) {
    Reserve(8);
    ByteWriter(buffer_.data() + used_).U64(v);
    used_ += 8;
  }
  void I32(int32_t v) {
    Reserve(4);
    ByteWriter(buffer_.data() + used_).I32(v);
    used_ += 4;
  }
  void F32(float v) {
    Reserve(4);
    ByteWriter(buffer_.data() + used_).F32(v);
    used_ += 4;
  }
  void Flush() {
    hash_->Update(std::string_view(buffer_.data(), used_));
    used_ = 0;
  }

 private:
  void Reserve(size_t n) {
    if (used_ + n > buffer_.size()) Flush();
  }

  Sha256* const hash_;
  std::string buffer_ = std::string(kChunkBytes, '\0');
  size_t used_ = 0;
};

}  // namespace

std::string ResultDigest(const std::vector<TileEvents>& result) {
  Sha256 hash;
  {
    DigestWriter out(&hash);
    out.U64(result.size());
    for (const TileEvents& tile : result) {
      out.I32(tile.tile_index);
      out.I32(tile.x0);
      out.I32(tile.y0);
      out.I32(tile.width);
      out.I32(tile.height);
      out.U64(tile.offsets.size());
      for (uint64_t offset : tile.offsets) out.U64(offset);
      out.U64(tile.events.size());
      for (const Event& e : tile.events) {
        out.F32(e.z);
        out.I32(e.count);
      }
    }
  }
  return hash.FinalHex();
}

}  // namespace pdsm
