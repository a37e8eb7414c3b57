#include "core/util/atomic_file.h"

#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "tests/test_support.h"

namespace pdsm {
namespace {

namespace fs = std::filesystem;

std::string Read(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

TEST(WriteFileAtomically, WritesThenReplacesLeavingNoTemporaryFile) {
  testing::TempDir dir;
  const std::string path = dir.File("a.csv");
  ASSERT_TRUE(WriteFileAtomically(path, "one\n").ok());
  EXPECT_EQ(Read(path), "one\n");
  ASSERT_TRUE(WriteFileAtomically(path, std::string("two\0three", 9)).ok());
  EXPECT_EQ(Read(path), std::string("two\0three", 9));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

TEST(WriteFileAtomically, MissingFolderIsInvalidArgumentNamingThePath) {
  testing::TempDir dir;
  const std::string path = dir.File("no/such/folder/a.csv");
  const absl::Status s = WriteFileAtomically(path, "x");
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << s;
  EXPECT_NE(s.message().find(path), std::string::npos) << s;
  EXPECT_TRUE(fs::is_empty(dir.path()));
}

TEST(WriteFileAtomically, FailedRenameKeepsTheOldTarget) {
  testing::TempDir dir;
  const std::string target = dir.File("target");
  fs::create_directory(target);  // a folder cannot be replaced by a file
  fs::create_directory(target + "/keep");
  const absl::Status s = WriteFileAtomically(target, "x");
  EXPECT_FALSE(s.ok());
  EXPECT_TRUE(fs::is_directory(target + "/keep"));
  EXPECT_EQ(std::distance(fs::directory_iterator(dir.path()), fs::directory_iterator()), 1);
}

}  // namespace
}  // namespace pdsm
