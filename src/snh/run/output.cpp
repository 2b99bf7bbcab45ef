#include "snh/run/output.hpp"

#include <cmath>
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

FrameWriter::FrameWriter(std::filesystem::path out, const VolumeMesh& mesh, bool write_vtu, const std::vector<bool>& pinned)
    : out_(std::move(out)),
      rest_(mesh.vertices),
      surface_(boundary_triangles(mesh)),
      faces_(obj_faces(surface_)),
      pinned_(Eigen::VectorXd::Zero(mesh.vertex_count())) {
  if (write_vtu) vtu_.emplace(mesh);
  for (std::size_t v = 0; v < pinned.size() && static_cast<Eigen::Index>(v) < pinned_.size(); ++v) pinned_[v] = pinned[v];
}

void FrameWriter::adopt_written(int last, const std::function<double(int)>& time) {
  series_.clear();
  if (!vtu_) return;
  for (int i = 0; i <= last; ++i) series_.emplace_back(time(i), fmt::format("{:03d}.vtu", i));
}

void FrameWriter::write(int index, double time, const Eigen::VectorXd& x, const ElasticTerm::Deformation& d) {
  const Eigen::Matrix3Xd X = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, x.size() / 3);
  write_obj(out_ / fmt::format("{:03d}.obj", index), X, faces_);
  if (!vtu_) return;
  const std::string vtu = fmt::format("{:03d}.vtu", index);
  vtu_->write(out_ / vtu, X, {{"displacement", X - rest_}}, {{"J", d.min_J}, {"psi", d.energy_density}}, {{"pinned", pinned_}});
  series_.emplace_back(time, vtu);
}

void FrameWriter::write_series() const {
  if (vtu_) write_pvd(out_ / "frames.pvd", series_);
}

}  // namespace snh
