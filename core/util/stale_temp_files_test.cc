// The file layer's answers to an interrupted writer: temporary files of dead writers are swept
// at the next start in the folder and those of live writers never are (the lock), SIGINT,
// SIGTERM and SIGHUP remove what is in flight, and nothing but a regular file or a new path is
// ever replaced.
#include <fcntl.h>
#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <filesystem>
#include <string>

#include "core/util/atomic_file.h"
#include "core/util/file_system.h"
#include "core/util/output_path.h"
#include "core/util/termination_cleanup.h"
#include "tests/test_support.h"
#include "tests/write_faults.h"

namespace pdsm {
namespace {

namespace fs = std::filesystem;
using ::pdsm::testing::FilesUnder;
using ::pdsm::testing::ReadBytes;
using ::pdsm::testing::TempDir;
using ::pdsm::testing::WriteText;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

TEST(IsTempFileName, MatchesOnlyTheNamesNewTempFileMakes) {
  EXPECT_TRUE(IsTempFileName("out.exr.tmp-a1B2c3"));
  EXPECT_TRUE(IsTempFileName("x.tmp-ZZZZZZ"));
  EXPECT_FALSE(IsTempFileName(".tmp-a1B2c3"));          // nothing before
  EXPECT_FALSE(IsTempFileName("out.exr.tmp-a1B2c"));    // five
  EXPECT_FALSE(IsTempFileName("out.exr.tmp-a1B2c34"));  // seven
  EXPECT_FALSE(IsTempFileName("out.exr.tmp-a1B2c3.bak"));
  EXPECT_FALSE(IsTempFileName("out.exr.tmp-a1B-c3"));
  EXPECT_FALSE(IsTempFileName("out.exr"));
}

TEST(RemoveStaleTempFiles, RemovesDeadWritersFilesAndKeepsLiveOnesAndOthers) {
  TempDir dir;
  FileSystem* files = FileSystem::Default();
  // A live writer: its file is locked until the AtomicFile goes.
  absl::StatusOr<std::unique_ptr<AtomicFile>> live = AtomicFile::Create(dir.File("live.exr"));
  ASSERT_TRUE(live.ok()) << live.status();
  ASSERT_TRUE((*live)->Append("in progress").ok());
  const std::string live_temp = fs::path((*live)->temp_path()).filename().string();
  // What a killed writer leaves: the same name, no lock.
  WriteText(dir.File("dead.exr.tmp-Ab3dE9"), "half a file");
  // Not ours, or not files: left alone.
  WriteText(dir.File("notes.tmp-short"), "x");
  WriteText(dir.File("dead.exr.tmp-Ab3dE9.keep"), "x");
  fs::create_directory(dir.File("folder.tmp-Ab3dE9"));
  fs::create_symlink(dir.File("notes.tmp-short"), dir.File("link.tmp-Ab3dE9"));

  EXPECT_EQ(files->RemoveStaleTempFiles(dir.path().string()), 1);
  EXPECT_FALSE(fs::exists(dir.File("dead.exr.tmp-Ab3dE9")));
  EXPECT_TRUE(fs::exists(dir.File(live_temp))) << "a live writer's file was taken";
  EXPECT_TRUE(fs::exists(dir.File("notes.tmp-short")));
  EXPECT_TRUE(fs::exists(dir.File("dead.exr.tmp-Ab3dE9.keep")));
  EXPECT_TRUE(fs::is_directory(dir.File("folder.tmp-Ab3dE9")));
  EXPECT_TRUE(fs::is_symlink(dir.File("link.tmp-Ab3dE9")));

  // Still locked after Close() inside Commit, until the rename: the writer finishes whole.
  ASSERT_TRUE((*live)->Commit().ok());
  EXPECT_EQ(ReadBytes(dir.File("live.exr")), "in progress");
  EXPECT_EQ(files->RemoveStaleTempFiles(dir.path().string()), 0);
}

// The lock is the kernel's: a writer in another process keeps its file, and the moment that
// process is killed (SIGKILL: no handler runs) the file becomes stale.
TEST(RemoveStaleTempFiles, KeepsAnotherProcesssFileUntilThatProcessIsKilled) {
  TempDir dir;
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(dir.File("out.exr"));
    if (!file.ok() || !(*file)->Append("partial").ok() || !(*file)->Flush().ok()) ::_exit(3);
    const char byte = 1;
    if (::write(ready[1], &byte, 1) != 1) ::_exit(4);
    ::pause();
    ::_exit(0);
  }
  ::close(ready[1]);
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ::close(ready[0]);
  ASSERT_EQ(FilesUnder(dir.path()).size(), 1u);
  EXPECT_EQ(FileSystem::Default()->RemoveStaleTempFiles(dir.path().string()), 0);
  EXPECT_EQ(FilesUnder(dir.path()).size(), 1u);
  ::kill(child, SIGKILL);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_EQ(FilesUnder(dir.path()).size(), 1u) << "SIGKILL runs no cleanup";
  EXPECT_EQ(FileSystem::Default()->RemoveStaleTempFiles(dir.path().string()), 1);
  EXPECT_THAT(FilesUnder(dir.path()), IsEmpty());
}

// A process's first write into a folder sweeps it: what a crash left there goes at the next
// start, without anyone running a cleanup command.
TEST(AtomicFile, FirstWriteInAFolderRemovesStaleTemporaryFiles) {
  TempDir dir;
  WriteText(dir.File("out.exr.tmp-Zz9Yy8"), "left by a killed bake");
  WriteText(dir.File("other.png.tmp-Qq1Ww2"), "left by another");
  ASSERT_TRUE(WriteFileAtomically(dir.File("first.csv"), "a").ok());
  EXPECT_THAT(FilesUnder(dir.path()), ElementsAre("first.csv"));
}

// The signal arrives while the writer is in flight; the child dies of that signal (the
// shell sees 128 + signal, as without the handler) and its temporary file is gone.
void ExpectSignalRemovesTemporaryFile(int signal_number) {
  TempDir dir;
  int ready[2];
  ASSERT_EQ(::pipe(ready), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    RemoveTempFilesOnTerminationSignals();
    absl::StatusOr<std::unique_ptr<AtomicFile>> file = AtomicFile::Create(dir.File("out.exr"));
    if (!file.ok() || !(*file)->Append("partial").ok() || !(*file)->Flush().ok()) ::_exit(3);
    const char byte = 1;
    if (::write(ready[1], &byte, 1) != 1) ::_exit(4);
    for (;;) ::pause();
  }
  ::close(ready[1]);
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ::close(ready[0]);
  ASSERT_EQ(FilesUnder(dir.path()).size(), 1u);
  ::kill(child, signal_number);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == signal_number) << status;
  EXPECT_THAT(FilesUnder(dir.path()), IsEmpty()) << "signal " << signal_number;
}

TEST(TerminationCleanup, SigintRemovesTheTemporaryFile) {
  ExpectSignalRemovesTemporaryFile(SIGINT);
}
TEST(TerminationCleanup, SigtermRemovesTheTemporaryFile) {
  ExpectSignalRemovesTemporaryFile(SIGTERM);
}
TEST(TerminationCleanup, SighupRemovesTheTemporaryFile) {
  ExpectSignalRemovesTemporaryFile(SIGHUP);
}

// A process started with SIGTERM ignored (nohup-style) keeps ignoring it.
TEST(TerminationCleanup, AnIgnoredSignalStaysIgnored) {
  int ready[2], go[2];
  ASSERT_EQ(::pipe(ready), 0);
  ASSERT_EQ(::pipe(go), 0);
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    ::signal(SIGTERM, SIG_IGN);
    RemoveTempFilesOnTerminationSignals();
    char byte = 1;
    if (::write(ready[1], &byte, 1) != 1) ::_exit(4);
    // The signal is sent before `go`, so a handled one would end the process in this read.
    if (::read(go[0], &byte, 1) != 1) ::_exit(5);
    ::_exit(7);
  }
  ::close(ready[1]);
  char byte = 0;
  ASSERT_EQ(::read(ready[0], &byte, 1), 1);
  ::close(ready[0]);
  ::kill(child, SIGTERM);
  ASSERT_EQ(::write(go[1], &byte, 1), 1);
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 7) << status;
}

TEST(CheckReplaceable, OnlyARegularFileOrANewPath) {
  TempDir dir;
  WriteText(dir.File("file"), "x");
  EXPECT_TRUE(CheckReplaceable(dir.File("file")).ok());
  EXPECT_TRUE(CheckReplaceable(dir.File("new")).ok());
  EXPECT_TRUE(CheckReplaceable(dir.File("no/such/folder/new")).ok());
  fs::create_directory(dir.File("folder"));
  ASSERT_EQ(::mkfifo(dir.File("fifo").c_str(), 0644), 0);
  fs::create_symlink(dir.File("file"), dir.File("link"));
  for (const auto& [path, what] :
       {std::pair<std::string, std::string>{"/dev/null", "character device"},
        {dir.File("folder"), "folder"},
        {dir.File("fifo"), "FIFO"},
        {dir.File("link"), "symbolic link"}}) {
    const absl::Status s = CheckReplaceable(path);
    EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << path;
    EXPECT_THAT(std::string(s.message()), HasSubstr(path));
    EXPECT_THAT(std::string(s.message()), HasSubstr(what));
  }
}

// The rename of an atomic write used to replace whatever node had the target's name (as root,
// `-o /dev/full` became a regular file). Now the writer refuses before creating anything.
TEST(AtomicFile, RefusesToReplaceAnythingButARegularFile) {
  TempDir dir;
  const std::string fifo = dir.File("fifo");
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0644), 0);
  WriteText(dir.File("real"), "kept");
  fs::create_symlink(dir.File("real"), dir.File("link"));
  for (const std::string& target : {fifo, dir.File("link")}) {
    const absl::Status s = WriteFileAtomically(target, "x");
    EXPECT_EQ(s.code(), absl::StatusCode::kFailedPrecondition) << s;
  }
  struct stat info;
  ASSERT_EQ(::lstat(fifo.c_str(), &info), 0);
  EXPECT_TRUE(S_ISFIFO(info.st_mode));
  EXPECT_TRUE(fs::is_symlink(dir.File("link")));
  EXPECT_EQ(ReadBytes(dir.File("real")), "kept");
  EXPECT_EQ(FilesUnder(dir.path()).size(), 1u) << "no temporary file";
}

TEST(CheckOutputPath, RefusesAnInputOfTheCommandHoweverItIsSpelled) {
  TempDir dir;
  const std::string scene = dir.File("scene.json");
  WriteText(scene, "{}");
  ASSERT_EQ(::link(scene.c_str(), dir.File("hard.json").c_str()), 0);
  for (const std::string& out :
       {scene, dir.File("./scene.json"), dir.File("sub/../scene.json"), dir.File("hard.json")}) {
    fs::create_directories(dir.File("sub"));
    const absl::Status s = CheckOutputPath("-o", out, {"-", "", dir.File("missing"), scene});
    EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument) << out;
    EXPECT_THAT(std::string(s.message()), HasSubstr("-o"));
    EXPECT_THAT(std::string(s.message()), HasSubstr("input"));
  }
  EXPECT_TRUE(CheckOutputPath("-o", dir.File("new.exr"), {scene}).ok());
  WriteText(dir.File("old.exr"), "x");
  EXPECT_TRUE(CheckOutputPath("-o", dir.File("old.exr"), {scene}).ok());
  const absl::Status device = CheckOutputPath("-o", "/dev/full", {scene});
  EXPECT_EQ(device.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(device.message()), HasSubstr("-o /dev/full"));
  EXPECT_EQ(CheckOutputPath("-o", "", {}).code(), absl::StatusCode::kInvalidArgument);
}

TEST(CheckOutputPaths, RefusesTwoOutputsThatAreOneFile) {
  TempDir dir;
  const absl::Status s = CheckOutputPaths(
      {{"--screenshot", dir.File("a.png")}, {"--save-attenuation", dir.File("x/../a.png")}}, {});
  EXPECT_EQ(s.code(), absl::StatusCode::kInvalidArgument);
  EXPECT_THAT(std::string(s.message()), HasSubstr("--screenshot"));
  EXPECT_TRUE(CheckOutputPaths({{"-o", dir.File("a.exr")}, {"--preview", ""}}, {}).ok());
}

}  // namespace
}  // namespace pdsm
