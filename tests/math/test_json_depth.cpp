// json_depth measures nesting without parsing: brackets in strings (escaped quotes included) do not count,
// and the scan stops once past the limit.
#include <gtest/gtest.h>

#include <string>

#include "snh/math/json_depth.hpp"

namespace snh {
namespace {

TEST(JsonDepth, CountsArraysAndObjectsNotStrings) {
  EXPECT_EQ(json_depth("", 10), 0u);
  EXPECT_EQ(json_depth("12", 10), 0u);
  EXPECT_EQ(json_depth("{}", 10), 1u);
  EXPECT_EQ(json_depth(R"({"a": [1, {"b": [[]]}], "c": {}})", 10), 5u);
  EXPECT_EQ(json_depth(R"({"a": "[[[{{{"})", 10), 1u);
  EXPECT_EQ(json_depth(R"({"a": "\"[[[", "b": []})", 10), 2u);  // an escaped quote does not end the string
  EXPECT_EQ(json_depth(R"(["\\", [[]]])", 10), 3u);          // an escaped backslash does not escape the quote
}

TEST(JsonDepth, StopsPastTheLimit) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  EXPECT_EQ(json_depth(deep, 64), 65u);
  EXPECT_EQ(json_depth(std::string(64, '[') + std::string(64, ']'), 64), 64u);
  EXPECT_EQ(json_depth("]]]}}[", 64), 1u);  // malformed: measured as far as it goes
}

}  // namespace
}  // namespace snh
