#include "snh/io/base64.hpp"

#include <cctype>

namespace snh {

std::string base64_encode(const void* data, std::size_t size) {
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const auto* b = static_cast<const unsigned char*>(data);
  std::string out;
  out.reserve(4 * ((size + 2) / 3));
  for (std::size_t i = 0; i < size; i += 3) {
    const unsigned v = (b[i] << 16) | (i + 1 < size ? b[i + 1] << 8 : 0) | (i + 2 < size ? b[i + 2] : 0);
    out += kAlphabet[(v >> 18) & 63];
    out += kAlphabet[(v >> 12) & 63];
    out += i + 1 < size ? kAlphabet[(v >> 6) & 63] : '=';
    out += i + 2 < size ? kAlphabet[v & 63] : '=';
  }
  return out;
}

bool base64_decode(std::string_view in, std::string& out) {
  // The 6-bit value of an alphabet character, or -1.
  const auto sextet = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
  };
  out.clear();
  unsigned pending = 0;  // bits not yet written out, the newest lowest
  int pending_bits = 0;
  for (const char c : in) {
    if (std::isspace(static_cast<unsigned char>(c))) continue;
    if (c == '=') {  // padding ends the stream: its leftover bits are dropped
      pending = 0;
      pending_bits = 0;
      continue;
    }
    const int v = sextet(c);
    if (v < 0) return false;
    pending = (pending << 6) | static_cast<unsigned>(v);
    pending_bits += 6;
    if (pending_bits >= 8) {
      pending_bits -= 8;
      out.push_back(static_cast<char>((pending >> pending_bits) & 0xFF));
    }
  }
  return true;
}

}  // namespace snh
