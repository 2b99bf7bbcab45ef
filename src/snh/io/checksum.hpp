#pragma once
// A 64-bit FNV-1a digest: detects changed bytes (any single changed byte changes it), for checkpoints
// and for fingerprints of the files a run reads. Not a cryptographic hash.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>
#include <string_view>

namespace snh {

/// FNV-1a over `size` bytes, continuing from `seed` (the offset basis by default).
[[nodiscard]] std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t seed = 14695981039346656037ull);
[[nodiscard]] inline std::uint64_t fnv1a64(std::string_view s) { return fnv1a64(s.data(), s.size()); }
/// The digest of a file's bytes as 16 hex digits. Throws std::runtime_error ("FILE: cannot read ...").
[[nodiscard]] std::string file_digest(const std::filesystem::path& path);

}  // namespace snh
