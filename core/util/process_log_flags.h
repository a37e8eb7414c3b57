// The --log-level and --log-format flags of the long-running binaries (pdsm-coordinator,
// pdsm-worker), which SetUpProcessLog (process_log.h) takes. Header-only: core itself does not
// parse command lines, only the binaries that include this do (CLI11).
#ifndef PDSM_CORE_UTIL_PROCESS_LOG_FLAGS_H_
#define PDSM_CORE_UTIL_PROCESS_LOG_FLAGS_H_

#include <CLI/CLI.hpp>

#include <iterator>
#include <string>
#include <vector>

#include "core/util/process_log.h"

namespace pdsm {

// Adds both flags to `app`, checked against the values SetUpProcessLog accepts; `level` and
// `format` hold the defaults shown in --help and receive the values given. Both must outlive
// the parse.
inline void AddProcessLogFlags(CLI::App& app, std::string* level, std::string* format) {
  app.add_option("--log-level", *level, "trace, debug, info, warn, error")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error"}))
      ->capture_default_str();
  app.add_option("--log-format", *format,
                 "text, or json: one object per line (time, level, component, message)")
      ->check(CLI::IsMember(
          std::vector<std::string>(std::begin(kLogFormatNames), std::end(kLogFormatNames))))
      ->capture_default_str();
}

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_PROCESS_LOG_FLAGS_H_
