#pragma once
// Base64 (RFC 4648): the encoder behind the report's Float32 arrays and the decoder behind the binary
// and appended data arrays of .vtu files.
#include <cstddef>
#include <string>
#include <string_view>

namespace snh {

/// Base64 of some bytes, padded with '=' to a multiple of 4 characters.
///   data  the first byte
///   size  how many bytes
[[nodiscard]] std::string base64_encode(const void* data, std::size_t size);

/// Decodes base64 whose padding may end one stream and start another (VTK encodes a data array's length
/// header and its values as two streams); white space is skipped.
///   in   the characters
///   out  the decoded bytes (cleared first)
/// Returns false at a character outside the alphabet.
[[nodiscard]] bool base64_decode(std::string_view in, std::string& out);

}  // namespace snh
