#pragma once
// The command line a program was started with, shell-quoted, for stats.json and the report.
#include <cctype>
#include <string>
#include <string_view>

namespace snh::cli {

/// argv joined by spaces; an argument that is empty or holds characters special to a shell is quoted.
inline std::string quoted_command_line(int argc, char** argv) {
  std::string out;
  for (int i = 0; i < argc; ++i) {
    const std::string a = argv[i];
    bool plain = !a.empty();
    for (char c : a)
      if (!(std::isalnum(static_cast<unsigned char>(c)) || std::string_view("-_./=:,+@%^").find(c) != std::string_view::npos))
        plain = false;
    if (i) out.push_back(' ');
    if (plain) {
      out += a;
      continue;
    }
    out.push_back('\'');  // (appended piece by piece: GCC 12 warns of a false overlap in `q = "'"`)
    for (char c : a) {
      if (c == '\'') out += "'\\''";
      else out.push_back(c);
    }
    out.push_back('\'');
  }
  return out;
}

/// The process' command line, set once by main().
inline std::string& invocation() {
  static std::string line;
  return line;
}

}  // namespace snh::cli
