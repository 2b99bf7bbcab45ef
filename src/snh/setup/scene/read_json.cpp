// A scene file's JSON, read strictly (issue 13): a key given twice in one object, a number out of double's
// range and nesting deeper than any scene needs are refused, each as one line naming the file and the key
// (or line) at fault. Built on nlohmann's SAX interface, its DOM builder doing the rest.
#include <algorithm>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/setup/scene.hpp"

namespace snh {
namespace {

using json = nlohmann::json;
constexpr std::size_t max_depth = 64;

class StrictReader {
 public:
  StrictReader(json& root, std::string_view text, const std::string& file) : dom_(root, true), text_(text), file_(file) {}

  bool null() { return dom_.null() && value(); }
  bool boolean(bool v) { return dom_.boolean(v) && value(); }
  bool number_integer(json::number_integer_t v) { return dom_.number_integer(v) && value(); }
  bool number_unsigned(json::number_unsigned_t v) { return dom_.number_unsigned(v) && value(); }
  bool number_float(json::number_float_t v, const json::string_t& s) { return dom_.number_float(v, s) && value(); }
  bool string(json::string_t& v) { return dom_.string(v) && value(); }
  bool binary(json::binary_t& v) { return dom_.binary(v) && value(); }
  bool start_object(std::size_t n) {
    push(true);
    return dom_.start_object(n);
  }
  bool key(json::string_t& k) {
    Frame& f = frames_.back();
    // No scene key holds a control character, and a key is written into messages as it is: one with a line
    // break (JSON's "\n") made a two-line message. Refused here, the key shown escaped.
    if (std::any_of(k.begin(), k.end(), [](char c) { return static_cast<unsigned char>(c) < 0x20 || c == '\x7f'; })) {
      f.key.clear();
      fail(path(), fmt::format("the key {} holds a control character (no scene key does)", json(k).dump(-1, ' ', false, json::error_handler_t::replace)));
    }
    f.key = k;
    if (!f.keys.insert(k).second) fail(path(), "the key is given twice in the same object (give each key once)");
    return dom_.key(k);
  }
  bool end_object() {
    frames_.pop_back();
    return dom_.end_object() && value();
  }
  bool start_array(std::size_t n) {
    push(false);
    return dom_.start_array(n);
  }
  bool end_array() {
    frames_.pop_back();
    return dom_.end_array() && value();
  }
  bool parse_error(std::size_t position, const std::string& token, const nlohmann::detail::exception& e) {
    if (e.id == 406) {  // a number beyond double's range (1e309): the lexer's own message names no file
      const std::size_t end = std::min(position, text_.size());
      const auto line = 1 + std::count(text_.begin(), text_.begin() + static_cast<std::ptrdiff_t>(end), '\n');
      throw SceneError(fmt::format("{}: line {}: number out of range: {}", file_, line,
                                   token.size() > 40 ? token.substr(0, 40) + "..." : token));
    }
    // nlohmann names line and column; its "[json.exception.parse_error.101] " tag is dropped.
    std::string what = e.what();
    if (what.rfind("[json.exception.", 0) == 0)
      if (const std::size_t at = what.find("] "); at != std::string::npos) what.erase(0, at + 2);
    throw SceneError(fmt::format("{}: not valid JSON: {}", file_, what));
  }

 private:
  struct Frame {
    bool object;
    std::set<std::string> keys;
    std::string key;
    std::size_t index = 0;
  };
  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw SceneError(fmt::format("{}: {}{}", file_, where.empty() ? "" : where + ": ", what));
  }
  void push(bool object) {
    if (frames_.size() >= max_depth) fail(path(), fmt::format("nested deeper than {} levels", max_depth));
    frames_.push_back({object, {}, {}, 0});
  }
  /// A value ended: the next one in an array has the next index.
  bool value() {
    if (!frames_.empty() && !frames_.back().object) ++frames_.back().index;
    return true;
  }
  /// Where the parser is, as the scene's messages write it: "pins[0].axes".
  std::string path() const {
    std::string p;
    for (const Frame& f : frames_) {
      if (f.object) {
        if (!f.key.empty()) p += (p.empty() ? "" : ".") + f.key;
      } else {
        p += fmt::format("[{}]", f.index);
      }
    }
    return p;
  }

  nlohmann::detail::json_sax_dom_parser<json> dom_;
  std::string_view text_;
  std::string file_;
  std::vector<Frame> frames_;
};

}  // namespace

nlohmann::json read_scene_json(std::string_view text, const std::string& file) {
  // JSON text holds no NUL byte (nlohmann's lexer took one for the end of the input: a scene followed by
  // NUL padding was read as if the padding were not there).
  if (const std::size_t nul = text.find('\0'); nul != std::string_view::npos)
    throw SceneError(fmt::format("{}: line {}: binary data (a NUL byte) where JSON text was expected", file,
                                 1 + std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(nul), '\n')));
  json j;
  StrictReader reader(j, text, file);
  (void)json::sax_parse(text, &reader);
  return j;
}

}  // namespace snh
