#pragma once
// Checks of the commands' option values. The --out option of the commands that write: an empty value is
// refused (it named no directory, and snh run/flesh silently fell back to their default one). Numbers: nan
// and ±inf are refused by every floating-point option, naming it ("--fps: must be a finite number, got nan").
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <string>

#include <CLI/CLI.hpp>

namespace snh::cli {

/// Check for an output path option: "is empty: give an output directory".
inline CLI::Validator non_empty_path(const std::string& what = "an output directory") {
  return CLI::Validator(
      [what](std::string& value) { return value.empty() ? "is empty: give " + what : std::string(); }, "", "NON_EMPTY");
}

/// Check for a number option: finite, and > 0 (`Sign::positive`) or >= 0 (`Sign::non_negative`) where asked.
enum class Sign { any, positive, non_negative };
inline CLI::Validator finite_number(Sign sign = Sign::any) {
  const char* name = sign == Sign::positive ? "POSITIVE" : sign == Sign::non_negative ? "NON_NEGATIVE" : "FINITE";
  return CLI::Validator(
      [sign](std::string& value) -> std::string {
        char* end = nullptr;
        errno = 0;
        const double v = std::strtod(value.c_str(), &end);
        if (end == value.c_str() || *end != '\0') return "expected a number, got " + value;
        if (!std::isfinite(v) || (errno == ERANGE && std::abs(v) > 1.0)) return "must be a finite number, got " + value;
        if (sign == Sign::positive && !(v > 0.0)) return "must be > 0, got " + value;
        if (sign == Sign::non_negative && !(v >= 0.0)) return "must be >= 0, got " + value;
        return {};
      },
      "", name);
}

/// Gives every floating-point option of `app` and of its subcommands the finite_number check.
inline void refuse_non_finite_numbers(CLI::App& app) {
  for (CLI::Option* option : app.get_options())
    if (option->get_type_name().rfind("FLOAT", 0) == 0) option->check(finite_number());
  for (CLI::App* sub : app.get_subcommands([](CLI::App*) { return true; })) refuse_non_finite_numbers(*sub);
}

}  // namespace snh::cli
