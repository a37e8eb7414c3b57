#include "core/pdsm/exr_scratch_stream.h"

#include <Iex.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "tests/test_support.h"

namespace pdsm {
namespace {

// 300 KiB of pseudo-random bytes at byte 1000 of a scratch file, read back through the stream
// in pieces small and large, across its 64 KiB buffer's edges, after seeks back and forth.
TEST(ExrScratchStream, ReadsItsRangeExactlyInAnyPieces) {
  testing::TempDir dir;
  absl::StatusOr<std::unique_ptr<ScratchFile>> file =
      FileSystem::Default()->NewScratchFile(dir.path().string());
  ASSERT_TRUE(file.ok()) << file.status();
  std::mt19937 rng(5);
  std::string bytes(300 << 10, '\0');
  for (char& c : bytes) c = static_cast<char>(rng());
  ASSERT_TRUE((*file)->WriteAt(0, std::string(1000, 'x')).ok());
  ASSERT_TRUE((*file)->WriteAt(1000, bytes).ok());
  ASSERT_TRUE((*file)->WriteAt(1000 + bytes.size(), std::string(1000, 'y')).ok());

  ExrScratchStream stream(file->get(), 1000, bytes.size());
  std::string got;
  std::uniform_int_distribution<int> piece(1, 100 << 10);
  std::vector<char> buffer(100 << 10);
  while (got.size() < bytes.size()) {
    const int n = std::min<int>(piece(rng), static_cast<int>(bytes.size() - got.size()));
    const bool more = stream.read(buffer.data(), n);
    got.append(buffer.data(), n);
    EXPECT_EQ(more, got.size() < bytes.size());
    EXPECT_EQ(stream.tellg(), got.size());
  }
  EXPECT_TRUE(got == bytes);
  for (uint64_t at : {uint64_t{70000}, uint64_t{3}, uint64_t{65535}, uint64_t{200000}}) {
    stream.seekg(at);
    char four[4];
    stream.read(four, 4);
    EXPECT_EQ(std::string(four, 4), bytes.substr(at, 4)) << at;
  }
  // Past the range's end, whatever the file holds after it: an input error, as at a file's end.
  stream.seekg(bytes.size() - 2);
  char four[4];
  EXPECT_THROW(stream.read(four, 4), Iex::InputExc);
}

}  // namespace
}  // namespace pdsm
