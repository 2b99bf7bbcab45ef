#pragma once
// Internal to the mesh readers (io/): a whole file read into memory, and a tokenizer over it that knows
// line numbers, so that every error names the file and line.
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "snh/io/input_file.hpp"
#include "snh/io/mesh_file.hpp"

namespace snh::detail {

namespace fs = std::filesystem;

/// Words longer than this are not text of a mesh file (a binary or damaged file): refused at once.
constexpr std::size_t max_word_chars = 4096;

/// The whole of a mesh or surface file. It must be a regular file of at most max_input_bytes
/// (input_file_problem: a directory, a FIFO, /dev/zero fail at once); `check_head`, when given, sees its
/// first bytes (up to 64 KiB) before the rest is read and throws if they are not of the format, so that
/// a large file of something else fails without being read. Throws MeshError naming the file.
inline std::string read_all(const fs::path& path, const std::function<void(const std::string& head)>& check_head = {}) {
  std::uintmax_t size = 0;
  if (const std::string problem = input_file_problem(path, "mesh file", &size); !problem.empty()) throw MeshError(problem);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(fmt::format("{}: cannot open the mesh file: {}", path.string(), std::strerror(errno)));
  std::string text(std::min<std::uintmax_t>(size, 64 * 1024), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (check_head) check_head(text);
  const std::size_t head = text.size();
  text.resize(static_cast<std::size_t>(size));
  in.read(text.data() + head, static_cast<std::streamsize>(text.size() - head));
  text.resize(head + static_cast<std::size_t>(in.gcount()));
  if (in.bad()) throw MeshError(fmt::format("{}: cannot read the mesh file", path.string()));
  return text;
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
    token_line_ = line_;
    while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_])) &&
           (comment_ == '\0' || text_[pos_] != comment_)) {
      if (text_[pos_] == '\0') fail("binary data (a NUL byte) where text was expected");
      if (pos_ - start >= max_word_chars)
        fail(fmt::format("a word longer than {} characters where text was expected", max_word_chars));
      ++pos_;
    }
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

/// A check_head for read_all: the head's first word (after comments) must be text and, when `magic` is
/// given, start with `magic` ("not FORMAT: it must start with MAGIC" otherwise). An empty head passes (the
/// reader reports the empty file).
inline std::function<void(const std::string&)> text_head(const fs::path& path, char comment, std::string magic = "",
                                                          std::string format = "") {
  return [=](const std::string& head) {
    Lexer lx(path, head, comment);
    const std::string_view w = lx.next();
    if (!magic.empty() && !w.empty() && w.substr(0, magic.size()) != magic)
      lx.fail(fmt::format("not {}: it must start with {}", format, magic));
  };
}

/// Fails unless only whitespace (and comments) follow: data after the end of a mesh (a NUL-padded or
/// damaged file) is refused, not ignored.
inline void expect_file_end(Lexer& lx, const char* after) {
  if (!lx.at_end()) {
    const std::string_view w = lx.next();  // fails itself on binary data
    lx.fail(fmt::format("unexpected '{}' after {}", w, after));
  }
}

}  // namespace snh::detail
