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
#include <memory>
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

/// The whole of a mesh or surface file (the readers that cannot parse as they read: VTU's XML, binary
/// STL). It must be a regular file of at most max_input_bytes (input_file_problem: a directory, a FIFO,
/// /dev/zero fail at once); `check_head`, when given, sees its first bytes (up to 64 KiB) before the rest
/// is read and throws if they are not of the format, so that a large file of something else fails without
/// being read. `text_until`, when given, says that everything before the first occurrence of that marker
/// (all of the file if there is none) is text: the read stops at the first NUL byte there, which is kept as
/// the last byte returned, so that a NUL-padded file is read only as far as its padding starts. Throws
/// MeshError naming the file.
inline std::string read_all(const fs::path& path, const std::function<void(const std::string& head)>& check_head = {},
                            std::string_view text_until = {}) {
  std::uintmax_t size = 0;
  if (const std::string problem = input_file_problem(path, "mesh file", &size); !problem.empty()) throw MeshError(problem);
  std::ifstream in(path, std::ios::binary);
  if (!in) throw MeshError(fmt::format("{}: cannot open the mesh file: {}", path.string(), std::strerror(errno)));
  std::string text;
  text.reserve(static_cast<std::size_t>(size));
  bool scan = !text_until.empty();  // still in the text part
  if (size == 0 && check_head) check_head(text);
  for (std::size_t chunk = 64 * 1024, scanned = 0; text.size() < size; chunk = scan ? 1024 * 1024 : size) {
    const std::size_t old = text.size(), n = static_cast<std::size_t>(std::min<std::uintmax_t>(chunk, size - old));
    text.resize(old + n);
    in.read(text.data() + old, static_cast<std::streamsize>(n));
    text.resize(old + static_cast<std::size_t>(in.gcount()));
    if (in.bad()) throw MeshError(fmt::format("{}: cannot read the mesh file", path.string()));
    if (old == 0 && check_head) check_head(text);
    if (scan) {
      const std::size_t nul = text.find('\0', scanned);
      const std::size_t marker = text.find(text_until, scanned > text_until.size() ? scanned - text_until.size() : 0);
      if (marker != std::string::npos && marker < nul) {
        scan = false;
      } else if (nul != std::string::npos) {
        text.resize(nul + 1);
        return text;
      }
      scanned = text.size();
    }
    if (text.size() == old) break;  // shorter than it was
  }
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
/// A lexer over a file (Lexer::open) reads it on demand, a chunk at a time, so that a file that goes wrong
/// (NUL padding after a valid mesh, binary junk) fails after reading about as much as was parsed, not all
/// of it; one over a string (the constructor) holds all of its text.
class Lexer {
 public:
  Lexer(const fs::path& file, std::string text, char comment = '\0')
      : file_(file.string()), text_(std::move(text)), comment_(comment), total_(text_.size()) {}
  /// The mesh file at path, read as it is parsed. It must be a regular file of at most max_input_bytes
  /// (input_file_problem: a directory, a FIFO, /dev/zero fail at once); `check_head`, when given, sees its
  /// first bytes (up to 64 KiB) before any more is read and throws if they are not of the format.
  static Lexer open(const fs::path& path, const std::function<void(const std::string& head)>& check_head = {},
                    char comment = '\0') {
    std::uintmax_t size = 0;
    if (const std::string problem = input_file_problem(path, "mesh file", &size); !problem.empty()) throw MeshError(problem);
    Lexer lx(path, std::string(), comment);
    lx.in_ = std::make_unique<std::ifstream>(path, std::ios::binary);
    if (!*lx.in_) throw MeshError(fmt::format("{}: cannot open the mesh file: {}", path.string(), std::strerror(errno)));
    lx.total_ = size;
    lx.text_.reserve(static_cast<std::size_t>(size));  // never reallocated: views of earlier tokens stay valid
    lx.more(64 * 1024);
    if (check_head) check_head(lx.text_);
    return lx;
  }
  [[noreturn]] void fail(const std::string& what, int line = -1) const {
    throw MeshError(fmt::format("{}:{}: {}", file_, line < 0 ? line_ : line, what));
  }
  /// The next token, or an empty view at the end.
  std::string_view next() {
    skip();
    const std::size_t start = pos_;
    token_line_ = line_;
    while (has() && !std::isspace(static_cast<unsigned char>(text_[pos_])) && (comment_ == '\0' || text_[pos_] != comment_)) {
      if (text_[pos_] == '\0') fail_binary();
      if (pos_ - start >= max_word_chars)
        fail(fmt::format("a word longer than {} characters where text was expected", max_word_chars));
      ++pos_;
    }
    return std::string_view(text_).substr(start, pos_ - start);
  }
  bool at_end() {
    skip();
    return !has();
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
  /// Moves to the end of the current line (its newline not taken); a NUL byte on the way is binary data.
  void skip_line() {
    while (has() && text_[pos_] != '\n') {
      if (text_[pos_] == '\0') fail_binary();
      ++pos_;
    }
  }
  /// The rest of the current line (without its newline, which is taken), its number in `line`; false at
  /// the end of the file. A NUL byte in it is binary data.
  bool rest_of_line(std::string& out, int& line) {
    if (!has()) return false;
    const std::size_t start = pos_;
    token_line_ = line = line_;
    skip_line();
    out.assign(text_, start, pos_ - start);
    if (has()) {
      ++pos_;
      ++line_;
    }
    return true;
  }
  /// Binary data starts after the newline that ends the current text line.
  void begin_binary() {
    if (has() && text_[pos_] == '\r') ++pos_;
    if (has() && text_[pos_] == '\n') ++pos_;
  }
  /// A little-endian value of type T read from the bytes at the current position.
  template <class T>
  T raw(const char* what) {
    if (!has(sizeof(T) - 1)) fail(fmt::format("the file ends inside binary data (reading {})", what));
    T v;
    std::memcpy(&v, text_.data() + pos_, sizeof(T));
    pos_ += sizeof(T);
    return v;
  }
  /// Moves past the next occurrence of `marker` (for skipping binary sections); false if there is none.
  bool skip_past(std::string_view marker) {
    std::size_t from = pos_, at = 0;
    while ((at = text_.find(marker, from)) == std::string::npos) {
      from = std::max(pos_, text_.size() - std::min(text_.size(), marker.size() - 1));
      if (!more()) return false;
    }
    line_ += static_cast<int>(std::count(text_.begin() + static_cast<std::ptrdiff_t>(pos_), text_.begin() + static_cast<std::ptrdiff_t>(at), '\n'));
    pos_ = at + marker.size();
    return true;
  }
  int line() const { return token_line_; }
  /// Bytes left after the current position, read or not (a bound for counts read from headers).
  std::size_t remaining() const { return total_ > pos_ ? static_cast<std::size_t>(total_ - pos_) : 0; }
  const std::string& file() const { return file_; }

 private:
  [[noreturn]] void fail_binary() const { fail("binary data (a NUL byte) where text was expected"); }
  /// Whether the byte k after the current position exists, reading more of the file if needed.
  bool has(std::size_t k = 0) {
    while (pos_ + k >= text_.size())
      if (!more()) return false;
    return true;
  }
  /// Appends up to `chunk` more bytes of the file (never past the size it had when opened); false at its end.
  bool more(std::size_t chunk = 1024 * 1024) {
    if (!in_ || text_.size() >= total_) return false;
    const std::size_t old = text_.size(), n = static_cast<std::size_t>(std::min<std::uintmax_t>(chunk, total_ - old));
    text_.resize(old + n);
    in_->read(text_.data() + old, static_cast<std::streamsize>(n));
    text_.resize(old + static_cast<std::size_t>(in_->gcount()));
    if (in_->bad()) fail("cannot read the mesh file");
    if (text_.size() == old) {  // shorter than it was: the end
      total_ = old;
      return false;
    }
    return true;
  }
  void skip() {
    while (has()) {
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
  std::uintmax_t total_;
  std::unique_ptr<std::ifstream> in_;
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
