// A corrupt PDSM against the command line (issue #17, finding 6): a small file whose string
// attribute claims 2 GB made `pdsm info` allocate 2 GB before exiting 2. Now it exits 2 naming
// the file with its memory bounded by the file, measured as the child's peak RSS.
#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>

#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/util/little_endian.h"
#include "tests/test_support.h"

extern char** environ;

namespace pdsm {
namespace {

using testing::ExamplePath;
using testing::ReadBytes;
using testing::RunCommand;
using testing::TempDir;
using testing::WriteText;

const std::string kPdsm = PDSM_CLI;

struct ChildRun {
  int exit_code = -1;
  long peak_rss_kib = 0;
  std::string err;
};

// Runs argv with stderr to a file; its exit code and peak resident memory (wait4).
ChildRun RunMeasured(const std::vector<std::string>& argv, const TempDir& dir) {
  const std::string err = dir.File("child.err");
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, "/dev/null", O_WRONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, err.c_str(),
                                   O_WRONLY | O_CREAT | O_TRUNC, 0644);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = -1;
  ChildRun run;
  if (posix_spawn(&pid, args[0], &actions, nullptr, args.data(), environ) == 0) {
    int status = 0;
    struct rusage usage {};
    if (wait4(pid, &status, 0, &usage) == pid && WIFEXITED(status)) {
      run.exit_code = WEXITSTATUS(status);
    }
    run.peak_rss_kib = usage.ru_maxrss;
  }
  posix_spawn_file_actions_destroy(&actions);
  run.err = ReadBytes(err);
  return run;
}

TEST(CorruptPdsm, AStringClaimingTwoGigabytesCostsNoMemoryAndExits2NamingTheFile) {
  TempDir dir;
  const std::string scene = ExamplePath("plates");
  const std::string good = dir.File("good.exr");
  ASSERT_EQ(RunCommand(kPdsm + " bake " + scene + " -o " + good +
                           " --resolution 128x128 --samples 16 --no-preview",
                       dir)
                .exit_code,
            0);
  std::string bytes = ReadBytes(good);
  // The size field of pdsmSceneName: after "pdsmSceneName\0string\0".
  const std::string record = std::string("pdsmSceneName\0string\0", 21);
  const size_t at = bytes.find(record);
  ASSERT_NE(at, std::string::npos);
  ByteWriter(&bytes[at + record.size()]).I32(0x7fffffff);
  const std::string corrupt = dir.File("corrupt.exr");
  WriteText(corrupt, bytes);
  ASSERT_LT(bytes.size(), 1u << 20);

  const std::string points = dir.File("points.csv");
  WriteText(points, "0,0,0\n1,0,1\n");
  const ChildRun baseline = RunMeasured({kPdsm, "info", good}, dir);
  ASSERT_EQ(baseline.exit_code, 0) << baseline.err;
  for (const std::vector<std::string>& argv :
       {std::vector<std::string>{kPdsm, "info", corrupt},
        std::vector<std::string>{kPdsm, "query", corrupt, "--points", points}}) {
    const ChildRun run = RunMeasured(argv, dir);
    EXPECT_EQ(run.exit_code, 2) << run.err;
    EXPECT_NE(run.err.find(corrupt), std::string::npos) << run.err;
    // 2 GB before; now what reading a good file of this size costs, give or take.
    EXPECT_LT(run.peak_rss_kib, baseline.peak_rss_kib + 64 * 1024)
        << argv[1] << ": peak " << run.peak_rss_kib << " KiB, a good file " << baseline.peak_rss_kib
        << " KiB";
  }
}

}  // namespace
}  // namespace pdsm
