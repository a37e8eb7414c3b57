// Helpers shared by the end-to-end tests: temporary folders, files, running the CLI.
#ifndef PDSM_TESTS_TEST_SUPPORT_H_
#define PDSM_TESTS_TEST_SUPPORT_H_

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include <gtest/gtest.h>
#include <sys/wait.h>

#include "core/pdsm/attenuation_function.h"

namespace pdsm {

// Readable failures for vertex comparisons (found by gtest through ADL).
inline void PrintTo(const Vertex& v, std::ostream* os) {
  *os << "(z=" << v.z << ", a=" << v.a << ")";
}

}  // namespace pdsm

namespace pdsm::testing {

// A fresh folder under the system temp dir, removed at destruction.
class TempDir {
 public:
  TempDir() {
    std::random_device rd;
    path_ = std::filesystem::temp_directory_path() /
            ("pdsm-test-" + std::to_string(rd()) + std::to_string(rd()));
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  std::string File(const std::string& name) const { return (path_ / name).string(); }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

inline void WriteText(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

inline std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

struct CommandResult {
  int exit_code = -1;
  std::string out;  // stdout
  std::string err;  // stderr
};

// Runs `command` through the shell; stdout and stderr captured separately.
inline CommandResult RunCommand(const std::string& command, const TempDir& dir) {
  const std::string out = dir.File("cmd.out"), err = dir.File("cmd.err");
  const int status = std::system((command + " >" + out + " 2>" + err).c_str());
  CommandResult result;
  result.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  result.out = ReadBytes(out);
  result.err = ReadBytes(err);
  return result;
}

inline std::string ExamplePath(const std::string& name) {
  return std::string(PDSM_SOURCE_DIR) + "/examples/" + name + "/scene.json";
}

// A scene small enough to bake in a fraction of a second: a 10 x 10 receiver-only floor, a
// 2 x 2 square 2 above it, a 1 x 1 rect light at 6; 48^2 PDSM, 16 samples, 16-pixel tiles.
inline constexpr char kTinySceneJson[] = R"({
  "name": "tiny",
  "meshes": [
    {"inline": {"positions": [-5,0,-5, 5,0,-5, 5,0,5, -5,0,5], "indices": [0,1,2, 0,2,3]},
     "role": "RECEIVER_ONLY"},
    {"inline": {"positions": [-1,2,-1, 1,2,-1, 1,2,1, -1,2,1], "indices": [0,1,2, 0,2,3]}}
  ],
  "light": {"rect": {"center": [0,6,0], "normal": [0,-1,0], "up": [0,0,1], "size": [1,1]}},
  "bake": {"resolution": [48,48], "samples": 16, "tileSize": 16}
})";

}  // namespace pdsm::testing

#endif  // PDSM_TESTS_TEST_SUPPORT_H_
