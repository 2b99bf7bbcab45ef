#include "snh/run/checkpoint.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

#include "snh/io/atomic_file.hpp"
#include "snh/io/checksum.hpp"
#include "snh/io/input_file.hpp"
#include "snh/material/printable.hpp"

namespace snh {
namespace {

// Version 2 ends with an FNV-1a digest of everything before it; version 1 (no digest) is refused.
constexpr char kMagic[8] = {'S', 'N', 'H', 'C', 'K', 'P', 'T', '2'};
constexpr char kMagicV1[8] = {'S', 'N', 'H', 'C', 'K', 'P', 'T', '1'};

template <class T>
void put(std::ostream& o, const T& v) {
  o.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

void put_vector(std::ostream& o, const Eigen::VectorXd& v) {
  put<std::uint64_t>(o, static_cast<std::uint64_t>(v.size()));
  o.write(reinterpret_cast<const char*>(v.data()), static_cast<std::streamsize>(v.size() * sizeof(double)));
}

}  // namespace

void write_checkpoint(const std::filesystem::path& dir, const Checkpoint& c) {
  std::ostringstream body;
  body.write(kMagic, sizeof(kMagic));
  put<std::uint64_t>(body, c.fingerprint.size());
  body.write(c.fingerprint.data(), static_cast<std::streamsize>(c.fingerprint.size()));
  put<std::int64_t>(body, c.step);
  put<double>(body, c.time);
  put_vector(body, c.x);
  put_vector(body, c.aux);
  const std::string bytes = body.str();
  write_atomically(dir / "checkpoint.bin", [&](std::ostream& o) {
    o.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    put<std::uint64_t>(o, fnv1a64(bytes));
  });
}

std::optional<Checkpoint> read_checkpoint(const std::filesystem::path& dir) {
  const std::filesystem::path path = dir / "checkpoint.bin";
  std::error_code ec;
  if (!std::filesystem::exists(std::filesystem::symlink_status(path, ec))) return std::nullopt;
  if (const std::string problem = input_file_problem(path, "checkpoint"); !problem.empty())
    throw std::runtime_error(problem);  // a FIFO or a device would block or never end
  std::ifstream in(path, std::ios::binary);
  if (!in) return std::nullopt;
  std::ostringstream buffer;
  buffer << in.rdbuf();
  const std::string bytes = buffer.str();
  std::size_t pos = 0;
  auto fail = [&](const char* what) -> void {
    throw std::runtime_error(fmt::format("{}: damaged checkpoint ({})", path.string(), what));
  };
  std::size_t limit = bytes.size();
  auto take = [&](void* out, std::size_t n) {
    if (limit - pos < n) fail("it ends early");
    if (n == 0) return;  // an empty vector's data() is null: no memcpy to it (fuzz_checkpoint, UBSan)
    std::memcpy(out, bytes.data() + pos, n);
    pos += n;
  };
  char magic[8];
  take(magic, sizeof(magic));
  if (std::memcmp(magic, kMagicV1, sizeof(magic)) == 0) fail("written by an older snh without a checksum: start the run again");
  if (std::memcmp(magic, kMagic, sizeof(magic)) != 0) fail("not an snh checkpoint");
  if (bytes.size() < sizeof(kMagic) + sizeof(std::uint64_t)) fail("it ends early");
  std::uint64_t digest = 0;
  std::memcpy(&digest, bytes.data() + bytes.size() - sizeof(digest), sizeof(digest));
  if (digest != fnv1a64(bytes.data(), bytes.size() - sizeof(digest)))
    fail("its checksum does not match: the file was changed or damaged");
  limit = bytes.size() - sizeof(digest);
  Checkpoint c;
  std::uint64_t n = 0;
  take(&n, sizeof(n));
  if (n > bytes.size()) fail("bad fingerprint length");
  c.fingerprint.resize(n);
  take(c.fingerprint.data(), n);
  std::int64_t step = 0;
  take(&step, sizeof(step));
  if (step < 0 || step > 100000000) fail("bad step");
  c.step = static_cast<int>(step);
  take(&c.time, sizeof(c.time));
  if (!std::isfinite(c.time) || c.time < 0) fail("bad time");
  for (Eigen::VectorXd* v : {&c.x, &c.aux}) {
    take(&n, sizeof(n));
    if (n > bytes.size() / sizeof(double)) fail("bad vector length");
    v->resize(static_cast<Eigen::Index>(n));
    take(v->data(), n * sizeof(double));
  }
  if (pos != limit) fail("trailing bytes");
  if (!c.x.allFinite() || !c.aux.allFinite()) fail("its state is not finite");
  return c;
}

std::vector<nlohmann::json> history_for_resume(const std::filesystem::path& dir, const char* key, int count) {
  std::error_code ec;
  if (const std::string problem = input_file_problem(dir / "stats.json", "stats file");
      !problem.empty() && std::filesystem::exists(std::filesystem::symlink_status(dir / "stats.json", ec)))
    throw std::invalid_argument(fmt::format("cannot resume: {}", problem));
  std::ifstream in(dir / "stats.json");
  if (!in) throw std::invalid_argument(fmt::format("cannot resume: {} has no stats.json", dir.string()));
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(in);
  } catch (const nlohmann::json::exception&) {
    throw std::invalid_argument(fmt::format("cannot resume: {}/stats.json is not valid JSON", dir.string()));
  }
  std::vector<nlohmann::json> out;
  for (const auto& entry : j.value(key, nlohmann::json::array())) {
    if (static_cast<int>(out.size()) == count) break;
    out.push_back(entry);
  }
  if (static_cast<int>(out.size()) != count)
    throw std::invalid_argument(fmt::format("cannot resume: {}/stats.json lists {} {}, the checkpoint needs {}", dir.string(),
                                            out.size(), key, count));
  return out;
}

Checkpoint checkpoint_for_resume(const std::filesystem::path& dir, const std::string& fingerprint, Eigen::Index dofs) {
  std::optional<Checkpoint> c;
  try {
    c = read_checkpoint(dir);
  } catch (const std::runtime_error& e) {
    throw std::invalid_argument(e.what());
  }
  if (!c) throw std::invalid_argument(fmt::format("cannot resume: {} has no checkpoint.bin (no step was completed there)", dir.string()));
  if (c->fingerprint != fingerprint)
    throw std::invalid_argument(fmt::format("cannot resume: the run in {} used other settings ({}; now {})", dir.string(),
                                            printable(c->fingerprint), printable(fingerprint)));
  // aux: a velocity or a previous solution (dofs), two previous solutions (2 dofs), or BDF2's velocity and
  // history (3 dofs + 1); Simulation::restore checks which its integrator takes.
  const Eigen::Index aux = c->aux.size();
  if (c->x.size() != dofs || (aux != dofs && aux != 2 * dofs && aux != 3 * dofs + 1))
    throw std::invalid_argument(fmt::format("cannot resume: the checkpoint in {} is for another mesh", dir.string()));
  return *c;
}

}  // namespace snh
