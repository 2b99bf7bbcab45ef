#pragma once
// Internal to the mesh readers (io/): a whole file read into memory, and a tokenizer over it that knows
// line numbers, so that every error names the file and line.
#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "snh/io/mesh_file.hpp"

namespace snh::detail {

namespace fs = std::filesystem;

inline std::string read_all(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(fmt::format("{}: cannot open the mesh file", path.string()));
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The value of attribute `name` in the XML tag that starts at `tag` (up to its '>'), or "".
inline std::string xml_attribute(std::string_view tag, std::string_view name) {
  const std::string key = fmt::format(" {}=\"", name);
  const std::size_t at = tag.find(key);
  if (at == std::string_view::npos) return "";
  const std::size_t start = at + key.size(), end = tag.find('"', start);
  return end == std::string_view::npos ? "" : std::string(tag.substr(start, end - start));
}

/// Whitespace-separated tokens with line numbers; `comment` starts a comment to the end of the line.
class Lexer {
 public:
  Lexer(const fs::path& file, std::string text, char comment = '\0')
      : file_(file.string()), text_(std::move(text)), comment_(comment) {}
  [[noreturn]] void fail(const std::string& what, int line = -1) const {
    throw MeshError(fmt::format("{}:{}: {}", file_, line < 0 ? line_ : line, what));
  }
  /// The next token, or an empty view at the end.
  std::string_view next() {
    skip();
    const std::size_t start = pos_;
    while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_])) && text_[pos_] != comment_) ++pos_;
    token_line_ = line_;
    return std::string_view(text_).substr(start, pos_ - start);
  }
  bool at_end() {
    skip();
    return pos_ >= text_.size();
  }
  std::string_view word(const char* what) {
    const std::string_view t = next();
    if (t.empty()) fail(fmt::format("the file ends where {} was expected", what));
    return t;
  }
  long long integer(const char* what) {
    const std::string_view t = word(what);
    long long v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec != std::errc() || end != t.data() + t.size()) fail(fmt::format("expected {} (an integer), got '{}'", what, t));
    return v;
  }
  long long count(const char* what, long long max = 1LL << 31) {
    const long long n = integer(what);
    if (n < 0 || n > max) fail(fmt::format("{} must be from 0 to {}, got {}", what, max, n));
    return n;
  }
  /// The next number; `finite_only` refuses inf and nan (data arrays may hold them: an undefined energy).
  double number(const char* what, bool finite_only = true) {
    const std::string_view t = word(what);
    double v = 0;
    const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
    if (ec == std::errc::result_out_of_range) fail(fmt::format("{} is out of range: '{}'", what, t));
    if (ec != std::errc() || end != t.data() + t.size()) fail(fmt::format("expected {} (a number), got '{}'", what, t));
    if (finite_only && !std::isfinite(v)) fail(fmt::format("{} is not finite: '{}'", what, t));
    return v;
  }
  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  }
  /// Binary data starts after the newline that ends the current text line.
  void begin_binary() {
    if (pos_ < text_.size() && text_[pos_] == '\r') ++pos_;
    if (pos_ < text_.size() && text_[pos_] == '\n') ++pos_;
  }
  /// A little-endian value of type T read from the bytes at the current position.
  template <class T>
  T raw(const char* what) {
    if (text_.size() - pos_ < sizeof(T)) fail(fmt::format("the file ends inside binary data (reading {})", what));
    T v;
    std::memcpy(&v, text_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  /// Moves past the next occurrence of `marker` (for skipping binary sections); false if there is none.
  bool skip_past(std::string_view marker) {
    const std::size_t at = text_.find(marker, pos_);
    if (at == std::string::npos) return false;
    line_ += static_cast<int>(std::count(text_.begin() + pos_, text_.begin() + at, '\n'));
    pos_ = at + marker.size();
    return true;
  }
  int line() const { return token_line_; }
  /// Bytes left after the current position (a bound for counts read from headers).
  std::size_t remaining() const { return text_.size() - pos_; }
  const std::string& file() const { return file_; }

 private:
  void skip() {
    while (pos_ < text_.size()) {
      const char c = text_[pos_];
      if (c == '\n') {
        ++line_;
        ++pos_;
      } else if (std::isspace(static_cast<unsigned char>(c))) {
        ++pos_;
      } else if (comment_ != '\0' && c == comment_) {
        skip_line();
      } else {
        break;
      }
    }
  }
  std::string file_, text_;
  char comment_;
  std::size_t pos_ = 0;
  int line_ = 1, token_line_ = 1;
};


}  // namespace snh::detail
