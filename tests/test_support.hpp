#pragma once
// Small helpers that several test files use (the test files are compiled together, eight to a translation
// unit: a helper they share lives here once, not in each file's anonymous namespace).
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <unistd.h>

namespace snh::test {

/// A 3×n matrix of points as one vector (x0, y0, z0, x1, …), and back.
inline Eigen::VectorXd flatten(const Eigen::Matrix3Xd& X) { return Eigen::Map<const Eigen::VectorXd>(X.data(), X.size()); }
inline Eigen::Matrix3Xd unflatten(const Eigen::VectorXd& x) { return Eigen::Map<const Eigen::Matrix3Xd>(x.data(), 3, x.size() / 3); }

/// The rotation by `angle` radians about `axis` (normalised here).
inline Eigen::Quaterniond about(const Eigen::Vector3d& axis, double angle) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(angle, axis.normalized()));
}

/// The whole contents of a file, read as bytes ("" when it cannot be read).
inline std::string file_text(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// A path in the temporary directory, `prefix + name + "_" + pid` (so that two test processes never share
/// it), with anything left there by an earlier run removed; the directory itself is not made.
inline std::filesystem::path fresh_dir(const std::string& prefix, const std::string& name) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / (prefix + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  return dir;
}

}  // namespace snh::test
