#include "client/measure/gnuplot.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstddef>

#include "absl/strings/str_format.h"
#include "core/util/file_system.h"

namespace pdsm {
namespace {

// Closes the descriptors it holds.
struct Pipe {
  int read = -1, write = -1;
  ~Pipe() {
    for (const int fd : {read, write}) {
      if (fd >= 0) ::close(fd);
    }
  }
};

absl::Status MakePipe(Pipe* pipe) {
  int fds[2];
  if (::pipe2(fds, O_CLOEXEC) != 0) return ErrnoStatus(errno, "cannot make a pipe for gnuplot");
  pipe->read = fds[0];
  pipe->write = fds[1];
  return absl::OkStatus();
}

// Puts all of `script` into the pipe, which is made large enough, then closes its write end:
// gnuplot starts with its whole input waiting, so nothing here can block on it or be killed
// by SIGPIPE if it dies.
absl::Status FillScriptPipe(const std::string& script, Pipe* pipe) {
  if (script.size() > 65536 &&
      ::fcntl(pipe->write, F_SETPIPE_SZ, static_cast<int>(script.size())) < 0) {
    const int error_number = errno;
    return ErrnoStatus(error_number,
                       absl::StrFormat("cannot pass a %d-byte script to gnuplot", script.size()));
  }
  ::fcntl(pipe->write, F_SETFL, O_NONBLOCK);
  for (size_t done = 0; done < script.size();) {
    const ssize_t n = ::write(pipe->write, script.data() + done, script.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return ErrnoStatus(errno, "cannot pass the script to gnuplot");
    done += static_cast<size_t>(n);
  }
  ::close(pipe->write);
  pipe->write = -1;
  return absl::OkStatus();
}

}  // namespace

absl::StatusOr<std::string> RunGnuplot(const std::string& script) {
  Pipe input, output;
  if (absl::Status s = MakePipe(&input); !s.ok()) return s;
  if (absl::Status s = FillScriptPipe(script, &input); !s.ok()) return s;
  if (absl::Status s = MakePipe(&output); !s.ok()) return s;
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_adddup2(&actions, input.read, STDIN_FILENO);
  posix_spawn_file_actions_adddup2(&actions, output.write, STDOUT_FILENO);
  char name[] = "gnuplot";
  char* argv[] = {name, nullptr};
  pid_t pid = 0;
  const int spawned = ::posix_spawnp(&pid, name, &actions, nullptr, argv, environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) return ErrnoStatus(spawned, "cannot run gnuplot");
  ::close(output.write);
  output.write = -1;
  std::string printed;
  int read_error = 0;
  char buffer[65536];
  for (;;) {
    const ssize_t n = ::read(output.read, buffer, sizeof(buffer));
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) read_error = errno;
    if (n <= 0) break;
    printed.append(buffer, static_cast<size_t>(n));
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  if (read_error != 0) return ErrnoStatus(read_error, "cannot read gnuplot's output");
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || printed.empty()) {
    return absl::InternalError(absl::StrFormat("gnuplot failed (wait status %d, %d bytes printed)",
                                               status, printed.size()));
  }
  return printed;
}

}  // namespace pdsm
