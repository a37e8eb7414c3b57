#include "core/scene/json_number_range.h"

#include <cctype>
#include <cmath>
#include <cstdlib>

#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

class Walker {
 public:
  explicit Walker(std::string_view text) : text_(text) {}

  // Returns false on malformed input or once an out-of-range number is found.
  bool Value(const std::string& path) {
    SkipSpace();
    if (pos_ >= text_.size()) return false;
    const char c = text_[pos_];
    if (c == '{') return Object(path);
    if (c == '[') return Array(path);
    if (c == '"') return String(nullptr);
    if (c == '-' || std::isdigit(static_cast<unsigned char>(c))) return Number(path);
    while (pos_ < text_.size() && std::isalpha(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    return true;  // true, false, null
  }

  const std::optional<OutOfRangeNumber>& found() const { return found_; }

 private:
  bool Object(const std::string& path) {
    ++pos_;
    SkipSpace();
    if (Peek('}')) return ++pos_, true;
    while (true) {
      SkipSpace();
      std::string key;
      if (!Peek('"') || !String(&key)) return false;
      SkipSpace();
      if (!Peek(':')) return false;
      ++pos_;
      if (!Value(path.empty() ? key : absl::StrCat(path, ".", key))) return false;
      SkipSpace();
      if (Peek(',')) {
        ++pos_;
        continue;
      }
      if (Peek('}')) return ++pos_, true;
      return false;
    }
  }

  bool Array(const std::string& path) {
    ++pos_;
    SkipSpace();
    if (Peek(']')) return ++pos_, true;
    for (int index = 0;; ++index) {
      if (!Value(absl::StrCat(path, "[", index, "]"))) return false;
      SkipSpace();
      if (Peek(',')) {
        ++pos_;
        continue;
      }
      if (Peek(']')) return ++pos_, true;
      return false;
    }
  }

  bool String(std::string* out) {
    ++pos_;  // opening quote
    while (pos_ < text_.size() && text_[pos_] != '"') {
      if (text_[pos_] == '\\') ++pos_;  // the escaped character is skipped whole
      if (out != nullptr && pos_ < text_.size()) out->push_back(text_[pos_]);
      ++pos_;
    }
    if (pos_ >= text_.size()) return false;
    ++pos_;
    return true;
  }

  bool Number(const std::string& path) {
    const size_t begin = pos_;
    while (pos_ < text_.size() && (std::isdigit(static_cast<unsigned char>(text_[pos_])) ||
                                   text_[pos_] == '-' || text_[pos_] == '+' ||
                                   text_[pos_] == '.' || text_[pos_] == 'e' ||
                                   text_[pos_] == 'E')) {
      ++pos_;
    }
    const std::string literal(text_.substr(begin, pos_ - begin));
    if (std::isinf(std::strtod(literal.c_str(), nullptr))) {
      found_ = OutOfRangeNumber{path, literal};
      return false;
    }
    return true;
  }

  void SkipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool Peek(char c) const { return pos_ < text_.size() && text_[pos_] == c; }

  std::string_view text_;
  size_t pos_ = 0;
  std::optional<OutOfRangeNumber> found_;
};

}  // namespace

std::optional<OutOfRangeNumber> FindOutOfRangeNumber(std::string_view json) {
  Walker walker(json);
  walker.Value("");
  return walker.found();
}

}  // namespace pdsm
