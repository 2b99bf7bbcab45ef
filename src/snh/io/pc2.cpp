#include "snh/io/pc2.hpp"

#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"

namespace snh {
namespace {

static_assert(std::endian::native == std::endian::little, "PC2 is little-endian: this writer assumes a little-endian machine");
constexpr char kMagic[12] = {'P', 'O', 'I', 'N', 'T', 'C', 'A', 'C', 'H', 'E', '2', '\0'};

template <class T>
void put(std::ostream& o, T v) {
  o.write(reinterpret_cast<const char*>(&v), sizeof v);
}

template <class T>
T take(std::istream& in, const std::filesystem::path& path) {
  T v{};
  if (!in.read(reinterpret_cast<char*>(&v), sizeof v)) throw std::runtime_error(fmt::format("{}: truncated PC2 file", path.string()));
  return v;
}

}  // namespace

void write_pc2(const std::filesystem::path& path, const std::vector<Eigen::Matrix3Xd>& samples, double start, double step) {
  if (samples.empty()) throw std::invalid_argument(fmt::format("{}: a point cache needs at least one sample", path.string()));
  const Eigen::Index points = samples.front().cols();
  if (points > std::numeric_limits<std::int32_t>::max() || samples.size() > static_cast<std::size_t>(std::numeric_limits<std::int32_t>::max()))
    throw std::invalid_argument(fmt::format("{}: too many points or samples for a PC2 file", path.string()));
  const double largest = static_cast<double>(std::numeric_limits<float>::max());
  for (std::size_t k = 0; k < samples.size(); ++k) {
    if (samples[k].cols() != points)
      throw std::invalid_argument(fmt::format("{}: sample {} has {} points, sample 0 has {}", path.string(), k, samples[k].cols(), points));
    if (!samples[k].allFinite() || samples[k].cwiseAbs().maxCoeff() > largest)
      throw std::invalid_argument(fmt::format("{}: sample {} has a point that is not a finite single-precision number", path.string(), k));
  }
  write_atomically(path, [&](std::ostream& o) {
    o.write(kMagic, sizeof kMagic);
    put<std::int32_t>(o, 1);
    put<std::int32_t>(o, static_cast<std::int32_t>(points));
    put<float>(o, static_cast<float>(start));
    put<float>(o, static_cast<float>(step));
    put<std::int32_t>(o, static_cast<std::int32_t>(samples.size()));
    std::vector<float> buffer(static_cast<std::size_t>(3 * points));
    for (const Eigen::Matrix3Xd& s : samples) {
      Eigen::Map<Eigen::Matrix3Xf>(buffer.data(), 3, points) = s.cast<float>();
      o.write(reinterpret_cast<const char*>(buffer.data()), static_cast<std::streamsize>(buffer.size() * sizeof(float)));
    }
  });
}

std::vector<Eigen::Matrix3Xd> read_pc2(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(fmt::format("{}: cannot open", path.string()));
  char magic[12];
  if (!in.read(magic, sizeof magic) || std::memcmp(magic, kMagic, sizeof magic) != 0)
    throw std::runtime_error(fmt::format("{}: not a PC2 file (no POINTCACHE2 header)", path.string()));
  const auto version = take<std::int32_t>(in, path);
  const auto points = take<std::int32_t>(in, path);
  take<float>(in, path);
  take<float>(in, path);
  const auto count = take<std::int32_t>(in, path);
  if (version != 1 || points < 0 || count < 0)
    throw std::runtime_error(fmt::format("{}: PC2 version {} with {} points and {} samples", path.string(), version, points, count));
  const auto size = static_cast<std::uintmax_t>(std::filesystem::file_size(path));
  if (size != 32 + 12ull * static_cast<std::uintmax_t>(points) * static_cast<std::uintmax_t>(count))
    throw std::runtime_error(fmt::format("{}: {} bytes, not the {} points x {} samples its header says", path.string(), size, points, count));
  std::vector<Eigen::Matrix3Xd> out;
  std::vector<float> buffer(3 * static_cast<std::size_t>(points));
  for (std::int32_t k = 0; k < count; ++k) {
    if (!in.read(reinterpret_cast<char*>(buffer.data()), static_cast<std::streamsize>(buffer.size() * sizeof(float))))
      throw std::runtime_error(fmt::format("{}: truncated PC2 file", path.string()));
    out.push_back(Eigen::Map<const Eigen::Matrix3Xf>(buffer.data(), 3, points).cast<double>());
  }
  return out;
}

}  // namespace snh
