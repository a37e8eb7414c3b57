#include "core/scene/json_number_range.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <vector>

#include "absl/strings/str_cat.h"

namespace pdsm {
namespace {

// Deeper than any scene (protobuf's own JSON parser stops at 100 levels): past it the walk
// gives up, and the real parser's error stands.
constexpr size_t kMaxDepth = 1000;

// An iterative walk with an explicit stack of open containers, so no input can overflow the
// call stack, and the field path is spelled out only for the one number it reports: the walk
// is linear in the text whatever the nesting.
class Walker {
 public:
  explicit Walker(std::string_view text) : text_(text) {}

  // Returns the out-of-range number, or nullopt (all fit, or the text is malformed).
  std::optional<OutOfRangeNumber> Run() {
    if (Value()) {
      while (!stack_.empty() && AfterValue()) {
      }
    }
    return found_;  // set only where the walk stopped at such a number
  }

 private:
  struct Open {
    bool object;
    std::string_view key;  // objects: the key of the current member
    int index = 0;         // arrays: the current element
  };

  // Reads one value; containers are pushed and their first member started. False on malformed
  // input, too deep a nesting, or once an out-of-range number is found.
  bool Value() {
    SkipSpace();
    if (pos_ >= text_.size()) return false;
    const char c = text_[pos_];
    if (c == '{' || c == '[') {
      if (stack_.size() >= kMaxDepth) return false;
      ++pos_;
      stack_.push_back(Open{c == '{', {}, 0});
      SkipSpace();
      if (Peek(c == '{' ? '}' : ']')) {
        ++pos_;
        stack_.pop_back();
        return true;
      }
      return c == '{' ? Key() && Value() : Value();
    }
    if (c == '"') return String(nullptr);
    if (c == '-' || std::isdigit(static_cast<unsigned char>(c))) return Number();
    while (pos_ < text_.size() && std::isalpha(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    return true;  // true, false, null
  }

  // After a member of the innermost container: the next member, or the container's end.
  bool AfterValue() {
    Open& open = stack_.back();
    SkipSpace();
    if (Peek(',')) {
      ++pos_;
      if (open.object) return Key() && Value();
      ++open.index;
      return Value();
    }
    if (Peek(open.object ? '}' : ']')) {
      ++pos_;
      stack_.pop_back();
      return true;
    }
    return false;
  }

  // `"key":` of the innermost object's next member.
  bool Key() {
    SkipSpace();
    std::string_view key;
    if (!Peek('"') || !String(&key)) return false;
    SkipSpace();
    if (!Peek(':')) return false;
    ++pos_;
    stack_.back().key = key;
    return true;
  }

  // `out`: the string's raw text between the quotes (keys are plain names).
  bool String(std::string_view* out) {
    const size_t begin = ++pos_;  // after the opening quote
    while (pos_ < text_.size() && text_[pos_] != '"') {
      if (text_[pos_] == '\\') ++pos_;  // the escaped character is skipped whole
      ++pos_;
    }
    if (pos_ >= text_.size()) return false;
    if (out != nullptr) *out = text_.substr(begin, pos_ - begin);
    ++pos_;
    return true;
  }

  bool Number() {
    const size_t begin = pos_;
    while (pos_ < text_.size() &&
           (std::isdigit(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '-' ||
            text_[pos_] == '+' || text_[pos_] == '.' || text_[pos_] == 'e' || text_[pos_] == 'E')) {
      ++pos_;
    }
    const std::string literal(text_.substr(begin, pos_ - begin));
    if (std::isinf(std::strtod(literal.c_str(), nullptr))) {
      found_ = OutOfRangeNumber{Path(), literal};
      return false;
    }
    return true;
  }

  // The field path of the value being read, e.g. "meshes[0].inline.positions[11]".
  std::string Path() const {
    std::string path;
    for (const Open& open : stack_) {
      if (open.object) {
        if (!path.empty()) path += '.';
        path.append(open.key);
      } else {
        absl::StrAppend(&path, "[", open.index, "]");
      }
    }
    return path;
  }

  void SkipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool Peek(char c) const { return pos_ < text_.size() && text_[pos_] == c; }

  std::string_view text_;
  size_t pos_ = 0;
  std::vector<Open> stack_;
  std::optional<OutOfRangeNumber> found_;
};

}  // namespace

std::optional<OutOfRangeNumber> FindOutOfRangeNumber(std::string_view json) {
  return Walker(json).Run();
}

}  // namespace pdsm
