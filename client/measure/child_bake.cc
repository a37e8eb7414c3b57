#include "client/measure/child_bake.h"

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>

#include "absl/strings/str_format.h"

namespace pdsm {
namespace {

std::string LastLine(const std::string& path) {
  std::ifstream in(path);
  std::string line, last;
  while (std::getline(in, line)) {
    // Progress bars redraw with '\r': keep the text after the last one.
    const size_t cr = line.rfind('\r');
    if (cr != std::string::npos) line = line.substr(cr + 1);
    if (!line.empty()) last = line;
  }
  return last;
}

}  // namespace

absl::StatusOr<ChildBakeResult> RunChildBake(const std::string& scene_path,
                                             const std::string& output_path,
                                             const std::vector<std::string>& args,
                                             const std::string& log_path) {
  std::vector<std::string> argv_strings = {"pdsm", "bake",      scene_path,
                                           "-o",   output_path, "--no-preview"};
  argv_strings.insert(argv_strings.end(), args.begin(), args.end());
  std::vector<char*> argv;
  for (std::string& s : argv_strings) argv.push_back(s.data());
  argv.push_back(nullptr);

  const int log_fd = open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (log_fd < 0) {
    return absl::InternalError(
        absl::StrFormat("%s: cannot create the log: %s", log_path, std::strerror(errno)));
  }
  const auto start = std::chrono::steady_clock::now();
  const pid_t pid = fork();
  if (pid == 0) {
    // Child: only async-signal-safe calls until exec.
    dup2(log_fd, STDOUT_FILENO);
    dup2(log_fd, STDERR_FILENO);
    execv("/proc/self/exe", argv.data());
    _exit(127);
  }
  close(log_fd);
  if (pid < 0) return absl::InternalError(absl::StrFormat("fork: %s", std::strerror(errno)));
  int status = 0;
  struct rusage usage {};
  while (wait4(pid, &status, 0, &usage) < 0) {
    if (errno != EINTR) {
      return absl::InternalError(absl::StrFormat("wait4: %s", std::strerror(errno)));
    }
  }
  ChildBakeResult result;
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  result.peak_rss_bytes = static_cast<uint64_t>(usage.ru_maxrss) * 1024;  // KiB on Linux
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code != 0) {
    const std::string message =
        absl::StrFormat("bake %s failed (%s; log %s): %s", output_path,
                        code < 0 ? "killed by a signal" : absl::StrFormat("exit %d", code),
                        log_path, LastLine(log_path));
    return code == 2 ? absl::InvalidArgumentError(message) : absl::InternalError(message);
  }
  std::error_code ec;
  result.file_bytes = std::filesystem::file_size(output_path, ec);
  return result;
}

}  // namespace pdsm
