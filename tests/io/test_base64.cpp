// Base64: RFC 4648's test vectors both ways, VTK's back-to-back padded streams, white space, and a
// character outside the alphabet.
#include <gtest/gtest.h>

#include <string>
#include <utility>
#include <vector>

#include "snh/io/base64.hpp"

namespace snh {
namespace {

const std::vector<std::pair<std::string, std::string>> kRfc4648 = {
    {"", ""}, {"f", "Zg=="}, {"fo", "Zm8="}, {"foo", "Zm9v"}, {"foob", "Zm9vYg=="}, {"fooba", "Zm9vYmE="}, {"foobar", "Zm9vYmFy"}};

TEST(Base64, Rfc4648Vectors) {
  for (const auto& [in, out] : kRfc4648) EXPECT_EQ(base64_encode(in.data(), in.size()), out) << in;
  const unsigned char high[] = {0xFF, 0xFE, 0x00, 0x80};
  EXPECT_EQ(base64_encode(high, 4), "//4AgA==");
}

TEST(Base64, DecodesTheVectorsAndEveryByteBack) {
  std::string bytes;
  for (const auto& [in, out] : kRfc4648) {
    ASSERT_TRUE(base64_decode(out, bytes)) << out;
    EXPECT_EQ(bytes, in) << out;
  }
  std::string all;
  for (int b = 0; b < 256; ++b) all.push_back(static_cast<char>(b));
  ASSERT_TRUE(base64_decode(base64_encode(all.data(), all.size()), bytes));
  EXPECT_EQ(bytes, all);
}

TEST(Base64, PaddedStreamsFollowOneAnotherAndWhiteSpaceIsSkipped) {
  std::string bytes = "left over";
  ASSERT_TRUE(base64_decode("Zg==\n Zm8=\tZm9v", bytes));  // "f", "fo", "foo" as three streams
  EXPECT_EQ(bytes, "ffofoo");
}

TEST(Base64, RefusesACharacterOutsideTheAlphabet) {
  std::string bytes;
  EXPECT_FALSE(base64_decode("Zm9v*", bytes));
  EXPECT_FALSE(base64_decode("Zm-v", bytes));
}

}  // namespace
}  // namespace snh
