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

void FrameWriter::adopt_written(int last, const std::function<double(int)>& time, const std::function<std::string(int)>& note) {
  series_.clear();
  notes_.clear();
  if (!vtu_) return;
  for (int i = 0; i <= last; ++i) {
    series_.emplace_back(time(i), fmt::format("{:03d}.vtu", i));
    notes_.push_back(note(i));
  }
}

void FrameWriter::write(int index, double time, const Eigen::VectorXd& x, const ElasticTerm::Deformation& d,
                        const std::string& prefix, const std::string& note) {
  const Eigen::Matrix3Xd X = Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, x.size() / 3);
  const std::string stem = prefix + fmt::format("{:03d}", index);
  write_obj(out_ / (stem + ".obj"), X, faces_);
  if (prefix.empty()) remove_failed_frame(out_, index, {".obj", ".vtu"});
  if (!vtu_) return;
  std::vector<std::pair<std::string, Eigen::VectorXd>> cells{{"J", d.min_J}, {"psi", d.energy_density}};
  if (d.contraction.size() > 0) cells.emplace_back("contraction", d.contraction);  // muscles
  vtu_->write(out_ / (stem + ".vtu"), X, {{"displacement", X - rest_}}, cells, {{"pinned", pinned_}});
  if (!prefix.empty()) return;
  series_.emplace_back(time, stem + ".vtu");
  notes_.push_back(note);
}

void FrameWriter::write_series() const {
  if (vtu_) write_pvd(out_ / "frames.pvd", series_, notes_);
}

void remove_failed_frame(const std::filesystem::path& dir, int index, std::initializer_list<const char*> extensions) {
  for (const char* ext : extensions) {
    std::error_code ec;  // nothing there is the usual case; anything else the next run's clearing reports
    std::filesystem::remove(dir / fmt::format("{}{:03d}{}", kFailedPrefix, index, ext), ec);
  }
}

}  // namespace snh
