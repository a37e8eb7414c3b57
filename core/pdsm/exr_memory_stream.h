// OpenEXR streams over memory: an output stream that fills a std::string (a chunk encoded on
// its own, a file's header made to be read back) and an input stream over bytes held
// elsewhere (such a file, read back). Not thread-safe.
#ifndef PDSM_CORE_PDSM_EXR_MEMORY_STREAM_H_
#define PDSM_CORE_PDSM_EXR_MEMORY_STREAM_H_

#include <OpenEXR/ImfIO.h>

#include <cstdint>
#include <string>
#include <string_view>

namespace pdsm {

// Writes at its own position (seekp moves it; a write past the end grows the string).
class ExrStringOStream final : public Imf::OStream {
 public:
  explicit ExrStringOStream(const char* name = "memory") : Imf::OStream(name) {}

  void write(const char c[], int n) override;
  uint64_t tellp() override { return position_; }
  void seekp(uint64_t pos) override { position_ = pos; }

  std::string& bytes() { return bytes_; }

 private:
  std::string bytes_;
  uint64_t position_ = 0;
};

// Reads `bytes`, which must outlive it. read() throws Iex::InputExc past the end, as OpenEXR
// expects of a file.
class ExrStringIStream final : public Imf::IStream {
 public:
  ExrStringIStream(std::string_view bytes, const char* name) : Imf::IStream(name), bytes_(bytes) {}

  bool read(char c[], int n) override;
  uint64_t tellg() override { return position_; }
  void seekg(uint64_t pos) override { position_ = pos; }

 private:
  const std::string_view bytes_;
  uint64_t position_ = 0;
};

}  // namespace pdsm

#endif  // PDSM_CORE_PDSM_EXR_MEMORY_STREAM_H_
