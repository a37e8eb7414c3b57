#include "server/request_checks.h"

#include "absl/strings/ascii.h"
#include "absl/strings/escaping.h"
#include "absl/strings/str_cat.h"

namespace pdsm {

absl::Status CheckJobId(absl::string_view id) {
  if (id.empty() || id.size() > kMaxJobIdBytes) {
    return absl::InvalidArgumentError(absl::StrCat("job_id: must have 1 to ", kMaxJobIdBytes,
                                                   " characters (got ", id.size(), ")"));
  }
  for (const char c : id) {
    if (!absl::ascii_isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-') {
      return absl::InvalidArgumentError("job_id: only letters, digits, '_' and '-' are allowed");
    }
  }
  return absl::OkStatus();
}

absl::Status CheckLightName(absl::string_view name) {
  // A light's name (64 bytes at most), or a sphere light's face: "NAME@+x".
  constexpr size_t kMaxLightNameBytes = 64 + 3;
  if (name.size() > kMaxLightNameBytes) {
    return absl::InvalidArgumentError(
        absl::StrCat("light: at most ", kMaxLightNameBytes, " characters (got ", name.size(), ")"));
  }
  for (const char c : name) {
    if (!absl::ascii_isalnum(static_cast<unsigned char>(c)) && c != '_' && c != '-' && c != '.' &&
        c != '@' && c != '+') {
      return absl::InvalidArgumentError(
          "light: only letters, digits, '_', '-', '.', and '@' and '+' of a sphere's face "
          "(\"lamp@+x\"), are allowed");
    }
  }
  return absl::OkStatus();
}

absl::Status CheckWorkerId(absl::string_view id) {
  if (id.empty() || id.size() > kMaxWorkerIdBytes) {
    return absl::InvalidArgumentError(absl::StrCat("worker_id: must have 1 to ", kMaxWorkerIdBytes,
                                                   " characters (got ", id.size(), ")"));
  }
  for (const char c : id) {
    if (c < 0x20 || c > 0x7e) {
      return absl::InvalidArgumentError(
          "worker_id: only printable ASCII characters are allowed (no control characters)");
    }
  }
  return absl::OkStatus();
}

std::string Printable(absl::string_view text, size_t max_bytes) {
  // CHexEscape escapes \, quotes, control and non-ASCII bytes; quotes may stay.
  std::string escaped = absl::CHexEscape(text);
  if (escaped.size() <= max_bytes) return escaped;
  escaped.resize(max_bytes);
  // Do not end inside an escape sequence ("\x1" would read as another byte).
  const size_t backslash = escaped.rfind('\\');
  if (backslash != std::string::npos && escaped.size() - backslash < 4) escaped.resize(backslash);
  absl::StrAppend(&escaped, "...(", text.size(), " bytes)");
  return escaped;
}

}  // namespace pdsm
