#pragma once
// After a run: its browser report beside its frames, and one line saying where it is.
#include <exception>
#include <filesystem>
#include <iostream>
#include <string>

#include "snh/report/report.hpp"

namespace snh::cli {

/// Writes the report of the run in `dir` and prints "report: PATH"; a failure is a warning on stderr
/// naming `program` (the run's own results stay) and returns false.
inline bool write_run_report(const std::filesystem::path& dir, const std::string& program) {
  try {
    const ReportSummary s = write_report(dir);
    std::cout << "report: " << std::filesystem::absolute(s.index).lexically_normal().string() << "\n";
    return true;
  } catch (const std::exception& e) {
    std::cerr << program << ": warning: the report was not written: " << e.what() << "\n";
    return false;
  }
}

}  // namespace snh::cli
