// Little-endian encoding of fixed-size values into, and out of, buffers sized in advance: the
// byte layouts of mesh asset blobs (core/assets) and stored tiles (server/tile_file) are the
// same on every machine.
#ifndef PDSM_CORE_UTIL_LITTLE_ENDIAN_H_
#define PDSM_CORE_UTIL_LITTLE_ENDIAN_H_

#include <bit>
#include <cstddef>
#include <cstdint>
#include <cstring>

namespace pdsm {

// REQUIRES: the buffer has room for everything written.
class ByteWriter {
 public:
  explicit ByteWriter(char* out) : out_(out) {}
  void Bytes(const char* data, size_t n) {
    std::memcpy(out_, data, n);
    out_ += n;
  }
  void U8(uint8_t v) { *out_++ = static_cast<char>(v); }
  void U16(uint16_t v) {
    for (int i = 0; i < 2; ++i) *out_++ = static_cast<char>(v >> (8 * i));
  }
  void U32(uint32_t v) {
    for (int i = 0; i < 4; ++i) *out_++ = static_cast<char>(v >> (8 * i));
  }
  void U64(uint64_t v) {
    for (int i = 0; i < 8; ++i) *out_++ = static_cast<char>(v >> (8 * i));
  }
  void I32(int32_t v) { U32(static_cast<uint32_t>(v)); }
  void F32(float v) { U32(std::bit_cast<uint32_t>(v)); }
  void F64(double v) { U64(std::bit_cast<uint64_t>(v)); }

 private:
  char* out_;
};

// REQUIRES: the caller checked that the bytes read are there.
class ByteReader {
 public:
  explicit ByteReader(const char* in) : in_(reinterpret_cast<const unsigned char*>(in)) {}
  uint8_t U8() { return *in_++; }
  uint16_t U16() {
    const uint16_t v = static_cast<uint16_t>(in_[0] | (in_[1] << 8));
    in_ += 2;
    return v;
  }
  void Bytes(char* out, size_t n) {
    std::memcpy(out, in_, n);
    in_ += n;
  }
  uint32_t U32() {
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v |= static_cast<uint32_t>(*in_++) << (8 * i);
    return v;
  }
  uint64_t U64() {
    uint64_t v = 0;
    for (int i = 0; i < 8; ++i) v |= static_cast<uint64_t>(*in_++) << (8 * i);
    return v;
  }
  int32_t I32() { return static_cast<int32_t>(U32()); }
  float F32() { return std::bit_cast<float>(U32()); }
  double F64() { return std::bit_cast<double>(U64()); }

 private:
  const unsigned char* in_;
};

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_LITTLE_ENDIAN_H_
