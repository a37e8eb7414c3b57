// What a command writes, and what it leaves when stopped (issue #17, findings 4 and 5): `-o`
// and every other output is a regular file or a new path and never one of the command's own
// inputs; new files get the umask's mode; a bake stopped by SIGTERM or SIGINT leaves no
// "OUT.tmp-XXXXXX"; one killed by SIGKILL leaves one, which the next command writing in that
// folder removes, while a bake still running there keeps its own. Real processes throughout.
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/pdsm/pdsm_file.h"
#include "core/util/file_system.h"
#include "tests/service/service_cluster.h"
#include "tests/test_support.h"

namespace pdsm {
namespace {

namespace fs = std::filesystem;
using testing::ChildProcess;
using testing::CommandResult;
using testing::ExamplePath;
using testing::ReadBytes;
using testing::RunCommand;
using testing::TempDir;
using testing::WriteText;

const std::string kPdsm = PDSM_CLI;

constexpr const char* kTinyScene = testing::kTinySceneJson;

// Names in `dir` that are temporary files of the atomic-write path.
std::vector<std::string> TempFilesIn(const TempDir& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir.path())) {
    const std::string name = entry.path().filename().string();
    if (IsTempFileName(name)) names.push_back(name);
  }
  return names;
}

std::string ModeOf(const std::string& path) {
  struct stat info;
  if (::lstat(path.c_str(), &info) != 0) return "missing";
  char text[8];
  std::snprintf(text, sizeof(text), "%04o", info.st_mode & 07777);
  return text;
}

void ExpectRefused(const CommandResult& r, const std::string& flag, const std::string& path) {
  EXPECT_EQ(r.exit_code, 2) << r.err;
  EXPECT_NE(r.err.find(flag + " " + path), std::string::npos) << r.err;
}

TEST(OutputSafety, BakeRefusesAnOutputThatIsNotARegularFileOrANewPath) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kTinyScene);
  fs::create_directory(dir.File("folder"));
  ASSERT_EQ(::mkfifo(dir.File("fifo").c_str(), 0644), 0);
  fs::create_symlink(dir.File("elsewhere.exr"), dir.File("link.exr"));
  std::vector<std::string> targets = {dir.File("folder"), dir.File("fifo"), dir.File("link.exr")};
  if (fs::exists("/dev/full")) targets.push_back("/dev/full");  // as root, it used to be replaced
  for (const std::string& target : targets) {
    const CommandResult r =
        RunCommand("timeout 120 " + kPdsm + " bake " + scene + " -o " + target, dir);
    ExpectRefused(r, "-o", target);
  }
  if (fs::exists("/dev/full")) {
    EXPECT_TRUE(fs::is_character_file("/dev/full"));
  }
  EXPECT_TRUE(fs::is_directory(dir.File("folder")));
  EXPECT_TRUE(fs::is_fifo(dir.File("fifo")));
  EXPECT_TRUE(fs::is_symlink(dir.File("link.exr")));
  EXPECT_FALSE(fs::exists(dir.File("elsewhere.exr")));
  EXPECT_TRUE(TempFilesIn(dir).empty());
}

TEST(OutputSafety, NoCommandOverwritesItsOwnInput) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kTinyScene);
  ASSERT_EQ(::link(scene.c_str(), dir.File("same.json").c_str()), 0);
  for (const std::string& out : {scene, dir.File("same.json"), dir.File("./tiny.json")}) {
    ExpectRefused(RunCommand(kPdsm + " bake " + scene + " -o " + out, dir), "-o", out);
  }
  ExpectRefused(
      RunCommand(kPdsm + " bake " + scene + " -o " + dir.File("o.exr") + " --preview " + scene,
                 dir),
      "--preview", scene);
  EXPECT_FALSE(fs::exists(dir.File("o.exr")));
  // The sweep's files are checked before it bakes anything.
  fs::create_directory(dir.File("sweep"));
  ASSERT_EQ(::mkfifo(dir.File("sweep/sweep.csv").c_str(), 0644), 0);
  ExpectRefused(
      RunCommand("timeout 120 " + kPdsm + " sweep " + scene + " --out " + dir.File("sweep"), dir),
      "--out", dir.File("sweep/sweep.csv"));
  // fetch checks -o before it connects (nothing listens on port 1).
  fs::create_directory(dir.File("d"));
  ExpectRefused(
      RunCommand(kPdsm + " fetch 0123456789abcdef -o " + dir.File("d") + " --server 127.0.0.1:1",
                 dir),
      "-o", dir.File("d"));
  // pdsm-view's outputs: not the scene, not the PDSM it reads.
  const std::string pdsm = dir.File("tiny.exr");
  ASSERT_EQ(RunCommand(kPdsm + " bake " + scene + " -o " + pdsm + " --no-preview", dir).exit_code,
            0);
  for (const auto& [flag, target] :
       {std::pair<std::string, std::string>{"--screenshot", scene}, {"--screenshot", pdsm}}) {
    ExpectRefused(RunCommand(std::string(PDSM_VIEW) + " " + scene + " --pdsm " + pdsm +
                                 " --headless --size 32x32 " + flag + " " + target,
                             dir),
                  flag, target);
  }
  ExpectRefused(RunCommand(std::string(PDSM_VIEW) + " " + scene + " --pdsm " + pdsm +
                               " --headless --size 32x32 --screenshot " + dir.File("v.png") +
                               " --save-attenuation " + scene,
                           dir),
                "--save-attenuation", scene);
  EXPECT_EQ(ReadBytes(scene), kTinyScene) << "the scene was overwritten";
  EXPECT_TRUE(TempFilesIn(dir).empty());
}

// mkstemp's 0600 is not the mode of a new file: every file a command makes gets 0666 less the
// umask, the PDSM and its preview as the sweep's CSV files.
TEST(OutputSafety, NewFilesGetTheUmasksMode) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kTinyScene);
  const CommandResult bake =
      RunCommand("umask 027 && " + kPdsm + " bake " + scene + " -o " + dir.File("out.exr"), dir);
  ASSERT_EQ(bake.exit_code, 0) << bake.err;
  EXPECT_EQ(ModeOf(dir.File("out.exr")), "0640");
  EXPECT_EQ(ModeOf(dir.File("out.png")), "0640");        // the camera view
  EXPECT_EQ(ModeOf(dir.File("out.light.png")), "0640");  // the map from the light
  const CommandResult sweep =
      RunCommand("umask 002 && " + kPdsm + " sweep " + scene + " --out " + dir.File("s") +
                     " --samples 4 --surface-points 20 --free-points 20 --reference-samples 16",
                 dir);
  ASSERT_EQ(sweep.exit_code, 0) << sweep.err;
  EXPECT_EQ(ModeOf(dir.File("s/sweep.csv")), "0664");
  EXPECT_EQ(ModeOf(dir.File("s/reference.csv")), "0664");
}

// A bake long enough to be caught in the middle, on one thread, writing `out`.
std::unique_ptr<ChildProcess> StartLongBake(const TempDir& dir, const std::string& out) {
  return std::make_unique<ChildProcess>(
      std::vector<std::string>{kPdsm, "bake", ExamplePath("plates"), "-o", out, "--threads", "1",
                               "--resolution", "512x512", "--samples", "256", "--no-preview"},
      dir.File(fs::path(out).filename().string() + ".log"));
}

// Waits until the bake's temporary file exists (the writer starts before the first tile).
bool WaitForTempFile(const TempDir& dir, ChildProcess& bake) {
  for (int i = 0; i < 1200; ++i) {
    if (!TempFilesIn(dir).empty()) return true;
    if (bake.Wait(std::chrono::milliseconds(0)) != -1) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  return false;
}

void ExpectSignalLeavesNoTemporaryFile(int signal_number) {
  TempDir dir;
  std::unique_ptr<ChildProcess> bake = StartLongBake(dir, dir.File("out.exr"));
  ASSERT_TRUE(WaitForTempFile(dir, *bake)) << ReadBytes(dir.File("out.exr.log"));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // into the tiles
  bake->Signal(signal_number);
  const int status = bake->Wait(std::chrono::seconds(60));
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number) << status;
  EXPECT_TRUE(TempFilesIn(dir).empty()) << "signal " << signal_number;
  EXPECT_FALSE(fs::exists(dir.File("out.exr")));
}

TEST(InterruptedBake, SigtermLeavesNoTemporaryFile) { ExpectSignalLeavesNoTemporaryFile(SIGTERM); }
TEST(InterruptedBake, SigintLeavesNoTemporaryFile) { ExpectSignalLeavesNoTemporaryFile(SIGINT); }

// SIGKILL runs nothing: the temporary file stays until the next command that writes in the
// folder sweeps it — but not the file of a bake still running there, started before the
// killed one (so its own start-up sweep is past) and still writing when the sweep comes.
TEST(InterruptedBake, SigkillsLeftoverIsSweptByTheNextRunButALiveBakesIsNot) {
  TempDir dir;
  const std::string scene = dir.File("tiny.json");
  WriteText(scene, kTinyScene);
  std::unique_ptr<ChildProcess> live = StartLongBake(dir, dir.File("live.exr"));
  ASSERT_TRUE(WaitForTempFile(dir, *live)) << ReadBytes(dir.File("live.exr.log"));
  const std::vector<std::string> live_temp = TempFilesIn(dir);
  ASSERT_EQ(live_temp.size(), 1u);
  {
    std::unique_ptr<ChildProcess> killed = StartLongBake(dir, dir.File("killed.exr"));
    for (int i = 0; i < 1200 && TempFilesIn(dir).size() < 2; ++i) {
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    ASSERT_EQ(TempFilesIn(dir).size(), 2u) << ReadBytes(dir.File("killed.exr.log"));
    killed->Signal(SIGKILL);
    killed->Wait(std::chrono::seconds(60));
  }
  ASSERT_EQ(TempFilesIn(dir).size(), 2u) << "SIGKILL runs no cleanup";

  const CommandResult next =
      RunCommand(kPdsm + " bake " + scene + " -o " + dir.File("next.exr") + " --no-preview", dir);
  ASSERT_EQ(next.exit_code, 0) << next.err;
  const bool still_running = live->Wait(std::chrono::milliseconds(0)) == -1;
  if (still_running) {
    EXPECT_EQ(TempFilesIn(dir), live_temp) << "swept the wrong file";
  } else {
    EXPECT_TRUE(TempFilesIn(dir).empty()) << "the killed bake's file was not swept";
  }
  const int status = live->Wait(std::chrono::seconds(600));
  ASSERT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
      << status << ReadBytes(dir.File("live.exr.log"));
  EXPECT_TRUE(ReadPdsm(dir.File("live.exr")).ok());
  EXPECT_TRUE(TempFilesIn(dir).empty());
}

}  // namespace
}  // namespace pdsm
