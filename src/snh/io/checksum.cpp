#include "snh/io/checksum.hpp"

#include <cerrno>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

namespace snh {

std::uint64_t fnv1a64(const void* data, std::size_t size, std::uint64_t seed) {
  const auto* b = static_cast<const unsigned char*>(data);
  std::uint64_t h = seed;
  for (std::size_t i = 0; i < size; ++i) {
    h ^= b[i];
    h *= 1099511628211ull;
  }
  return h;
}

std::string file_digest(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot read the file: {}", path.string(), std::strerror(errno)));
  std::uint64_t h = 14695981039346656037ull;
  std::vector<char> buffer(1 << 16);
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    h = fnv1a64(buffer.data(), static_cast<std::size_t>(in.gcount()), h);
  }
  if (in.bad()) throw std::runtime_error(fmt::format("{}: cannot read the file", path.string()));
  return fmt::format("{:016x}", h);
}

}  // namespace snh
