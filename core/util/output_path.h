// The check every command runs on each path it will write, before doing any work: an output
// must be a regular file or a new path, and must not be one of the command's own inputs.
// `-o /dev/full` run as root used to replace the device node with a regular file (the rename
// of the atomic write), and `-o SCENE.json` overwrote the scene it was baking.
#ifndef PDSM_CORE_UTIL_OUTPUT_PATH_H_
#define PDSM_CORE_UTIL_OUTPUT_PATH_H_

#include <string>
#include <utility>
#include <vector>

#include "absl/status/status.h"
#include "absl/strings/string_view.h"

namespace pdsm {

// INVALID_ARGUMENT "<flag> <path>: ..." when `path` exists and is not a regular file (a
// device, a folder, a FIFO, a socket, a symbolic link: CheckReplaceable in file_system.h), or
// when it is the same file as one of `inputs` (same device and inode, so another spelling or
// a hard link counts too; "-" and inputs that do not exist are skipped). A path that does not
// exist is fine: whether its folder can be written is the writer's error to report. Checked
// once here to refuse early, and again by the writer (AtomicFile) when it starts and just
// before its rename.
absl::Status CheckOutputPath(absl::string_view flag, const std::string& path,
                             const std::vector<std::string>& inputs);

// A command's outputs as (flag, path); empty paths are skipped.
using OutputPaths = std::vector<std::pair<std::string, std::string>>;

// CheckOutputPath for each output, and INVALID_ARGUMENT naming both flags when two outputs
// are the same path (compared after making them absolute and normal: "a/../b" is "b").
absl::Status CheckOutputPaths(const OutputPaths& outputs, const std::vector<std::string>& inputs);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_OUTPUT_PATH_H_
