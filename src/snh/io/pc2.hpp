#pragma once
// PC2 point caches (docs/formats.md "PC2"): the positions of a mesh's vertices at every frame, the format
// of 3ds Max's Point Cache 2 that Blender's Mesh Cache modifier reads. A 32-byte header
// ("POINTCACHE2\0", version 1, the point count, the first frame, the frames between samples, the sample
// count; little-endian 32-bit integers and floats) and then every sample's points as three 32-bit floats.
#include <filesystem>
#include <vector>

#include <Eigen/Core>

namespace snh {

/// Writes the samples (each 3 by #points, all of one size) atomically, sample k at frame start + k · step.
/// Throws std::invalid_argument for no samples, samples of differing sizes or a point that is not finite in
/// single precision; WriteError when the file cannot be written.
void write_pc2(const std::filesystem::path& path, const std::vector<Eigen::Matrix3Xd>& samples, double start = 0.0,
               double step = 1.0);

/// Reads a PC2 file (the samples, each 3 by #points). Throws std::runtime_error naming the file for a file
/// that is not one.
[[nodiscard]] std::vector<Eigen::Matrix3Xd> read_pc2(const std::filesystem::path& path);

}  // namespace snh
