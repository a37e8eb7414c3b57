// The log of a long-running pdsm process (coordinator, worker): one named spdlog logger on
// stderr, in one of two formats.
//   text: spdlog's default pattern with the component name, for people and journald;
//   json: one object per line, for log shippers (Loki, Elasticsearch, Cloud Logging):
//         {"time":"2026-12-02T03:04:05.678Z","level":"info","component":"worker",
//          "message":"..."} with the time in UTC (RFC 3339, milliseconds), the level as
//         spdlog names it (trace, debug, info, warning, error, critical) and the message
//         JSON-escaped (control characters as \u00XX; invalid UTF-8 bytes as U+FFFD), so
//         every line parses whatever a message holds.
// Call once, before any thread logs. Not thread-safe itself; the logger it installs is.
#ifndef PDSM_CORE_UTIL_PROCESS_LOG_H_
#define PDSM_CORE_UTIL_PROCESS_LOG_H_

#include <string>
#include <string_view>

namespace pdsm {

// The names --log-format accepts.
inline constexpr const char* kLogFormatNames[] = {"text", "json"};

// REQUIRES: `format` is one of kLogFormatNames and `level` one of trace, debug, info, warn,
// error (the flags check both).
void SetUpProcessLog(const std::string& component, const std::string& level,
                     const std::string& format);

// `text` as the body of a JSON string (no quotes around it): the escaping the json format
// uses, exposed for its tests.
std::string JsonEscapedForLog(std::string_view text);

}  // namespace pdsm

#endif  // PDSM_CORE_UTIL_PROCESS_LOG_H_
