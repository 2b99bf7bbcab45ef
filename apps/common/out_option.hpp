#pragma once
// The --out option of the commands that write: an empty value is refused (it named no directory, and
// snh run/flesh silently fell back to their default one).
#include <string>

#include <CLI/CLI.hpp>

namespace snh::cli {

/// Check for an output path option: "is empty: give an output directory".
inline CLI::Validator non_empty_path(const std::string& what = "an output directory") {
  return CLI::Validator(
      [what](std::string& value) { return value.empty() ? "is empty: give " + what : std::string(); }, "", "NON_EMPTY");
}

}  // namespace snh::cli
