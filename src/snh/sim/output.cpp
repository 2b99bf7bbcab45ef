#include "snh/sim/output.hpp"

#include <fstream>

#include <fmt/format.h>

#include "snh/io/obj.hpp"
#include "snh/io/vtu.hpp"
#include "snh/mesh/surface.hpp"

namespace snh {

double peak_memory_mib() {
  std::ifstream in("/proc/self/status");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("VmHWM:", 0) == 0) return std::stod(line.substr(6)) / 1024.0;  // reported in kB
  return 0.0;
}

FrameWriter::FrameWriter(std::filesystem::path out, const VolumeMesh& mesh, bool write_vtu)
    : out_(std::move(out)), mesh_(mesh), surface_(boundary_triangles(mesh)), write_vtu_(write_vtu) {}

void FrameWriter::adopt_written(int last, const std::function<double(int)>& time) {
  series_.clear();
  if (!write_vtu_) return;
  for (int i = 0; i <= last; ++i) series_.emplace_back(time(i), fmt::format("{:03d}.vtu", i));
}

void FrameWriter::write(int index, double time, const Eigen::VectorXd& x, const Eigen::VectorXd& min_J) {
  const Eigen::Matrix3Xd X = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, x.size() / 3);
  write_obj(out_ / fmt::format("{:03d}.obj", index), X, surface_);
  if (!write_vtu_) return;
  const std::string vtu = fmt::format("{:03d}.vtu", index);
  write_vtu(out_ / vtu, mesh_, X, {{"displacement", X - mesh_.vertices}}, {{"J", min_J}});
  series_.emplace_back(time, vtu);
  write_pvd(out_ / "frames.pvd", series_);
}

}  // namespace snh
