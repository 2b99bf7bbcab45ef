#pragma once
// Reading a glTF file into tinygltf's model, with every file it names checked (internal to the glTF reader).
//
// Debian's libtinygltf is built with its stb_image loaders and file-system callbacks, so the header is
// included as is (no TINYGLTF_NO_* macros: the defaults the header's inline constructor names are the
// library's). Images are never decoded (a loader that ignores them is installed before every load), and
// the files of external images are not read.
#include <filesystem>

#include <tiny_gltf.h>

namespace snh::gltf {

/// The file parsed by tinygltf: a GLB container if it starts with "glTF", else glTF JSON. The file and
/// each external buffer must be a regular file of at most rig_build::max_file_bytes, read no further than
/// its size; a GLB's header length must be its size; the JSON nests at most 64 levels. Throws RigError (one
/// line naming the file) otherwise, or where tinygltf refuses it.
[[nodiscard]] tinygltf::Model load(const std::filesystem::path& path);

}  // namespace snh::gltf
