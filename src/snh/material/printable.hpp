#pragma once
// Names echoed in error messages, made printable: a NUL byte cut the message there (what() is a C
// string) and other control bytes garbled the terminal.
#include <string>
#include <string_view>

namespace snh {

/// `text` with every byte outside printable ASCII (0x20-0x7e) written as \xNN and a backslash as \\.
[[nodiscard]] inline std::string printable(std::string_view text) {
  static constexpr char kHex[] = "0123456789abcdef";
  std::string out;
  out.reserve(text.size());
  for (const char ch : text) {
    const auto c = static_cast<unsigned char>(ch);
    if (c == '\\') {
      out += "\\\\";
    } else if (c >= 0x20 && c < 0x7f) {
      out += ch;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
    }
  }
  return out;
}

}  // namespace snh
