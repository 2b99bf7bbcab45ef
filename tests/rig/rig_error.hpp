#pragma once
// The check the model readers' tests share: reading a file fails with a RigError of one line that names the
// file and says what is wrong.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "snh/rig/model.hpp"

namespace snh::test {

/// read(path) throws a RigError whose message is one line, starts with "PATH: " and contains `fragment`.
template <class Read>
void expect_rig_error(const Read& read, const std::filesystem::path& path, const std::string& fragment) {
  try {
    (void)read(path);
    ADD_FAILURE() << path << " was read";
  } catch (const RigError& e) {
    const std::string what = e.what();
    EXPECT_EQ(what.find('\n'), std::string::npos) << what;
    EXPECT_EQ(what.rfind(path.string() + ": ", 0), 0u) << what;
    EXPECT_NE(what.find(fragment), std::string::npos) << what;
  }
}

}  // namespace snh::test
