#include "snh/rig/gltf_load.hpp"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/math/json_depth.hpp"
#include "snh/rig/model_build.hpp"

namespace snh::gltf {
namespace {

namespace fs = std::filesystem;
using rig_build::check_file;
using rig_build::fail;
using rig_build::one_line;

/// The whole file, checked to be a readable regular file of a sensible size, followed by 16 zero bytes (a
/// margin for tinygltf's GLB chunk parsing, which may look a few bytes past a chunk that ends the file).
std::vector<unsigned char> read_file(const fs::path& path, std::size_t& size) {
  const std::uintmax_t n = check_file(path, "glTF");
  std::ifstream in(path, std::ios::binary);
  if (!in) fail(path, "cannot open the file");
  // A GLB's header says its length: checked before the rest is read, so that a file of something else named
  // .glb, or a GLB with hundreds of megabytes after its end, is refused without reading it whole.
  unsigned char head[12] = {};
  in.read(reinterpret_cast<char*>(head), 12);
  const auto got = static_cast<std::uintmax_t>(in.gcount());
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  if (got >= 4 && std::memcmp(head, "glTF", 4) == 0) {
    std::uint32_t length = 0;
    if (got == 12) std::memcpy(&length, head + 8, 4);
    if (got < 12 || length != n)
      fail(path, fmt::format("not a valid glTF binary: its header says {} bytes, the file has {}", got < 12 ? 0 : length, n));
    std::uint32_t version = 0;
    std::memcpy(&version, head + 4, 4);
    if (version != 2) fail(path, fmt::format("a glTF binary of version {}: snh reads version 2", version));
  } else if (ext == ".glb") {
    fail(path, "not a glTF binary (it does not start with \"glTF\")");
  }
  in.seekg(0);
  std::vector<unsigned char> bytes(static_cast<std::size_t>(n) + 16, 0);
  in.read(reinterpret_cast<char*>(bytes.data()), static_cast<std::streamsize>(n));
  if (static_cast<std::uintmax_t>(in.gcount()) != n)
    fail(path, fmt::format("cannot read the file (read {} of {} bytes)", in.gcount(), n));
  size = static_cast<std::size_t>(n);
  return bytes;
}

/// The files a glTF names, as tinygltf will ask for them (their URIs decoded, joined to the model's directory
/// and to "."), normalised: its images' and its buffers', each buffer's with the byteLength it must have.
struct NamedFiles {
  /// Not read at all: snh never decodes an image (tinygltf takes a failed read of an image as a warning), and
  /// an unused 900 MB texture used to cost its size in memory. Less any file that a buffer names too.
  std::vector<fs::path> images;
  /// Refused without being read when their size is not the length the glTF gives (a 900 MB .bin for a buffer
  /// of 1 kB was read whole before tinygltf's "File size mismatch").
  std::vector<std::pair<fs::path, std::uintmax_t>> buffers;
};

NamedFiles named_files(std::string_view json_text, const std::string& base) {
  NamedFiles out;
  const nlohmann::json j = nlohmann::json::parse(json_text, nullptr, false);
  if (j.is_discarded() || !j.is_object()) return out;
  // Each external file of the list `key` with the object naming it.
  const auto each_file = [&](const char* key, const auto& take) {
    const auto list = j.find(key);
    if (list == j.end() || !list->is_array()) return;
    for (const nlohmann::json& e : *list) {
      const auto uri = e.is_object() ? e.find("uri") : e.end();
      if (uri == e.end() || !uri->is_string() || uri->get<std::string>().rfind("data:", 0) == 0) continue;
      std::string decoded;  // as tinygltf decodes a URI: %XX a byte, + a space
      const std::string text = uri->get<std::string>();
      for (std::size_t i = 0; i < text.size(); ++i) {
        if (text[i] == '+') decoded += ' ';
        else if (text[i] == '%' && i + 2 < text.size()) {
          const auto hex = [](char c) {
            return c >= '0' && c <= '9' ? c - '0' : c >= 'a' && c <= 'f' ? c - 'a' + 10 : c >= 'A' && c <= 'F' ? c - 'A' + 10 : 0;
          };
          decoded += static_cast<char>(hex(text[i + 1]) << 4 | hex(text[i + 2]));
          i += 2;
        } else decoded += text[i];
      }
      for (const std::string& dir : {base, std::string(".")})
        take(fs::path(dir.empty() ? decoded : dir + (dir.back() == '/' ? "" : "/") + decoded).lexically_normal(), e);
    }
  };
  each_file("buffers", [&](const fs::path& p, const nlohmann::json& e) {
    const auto length = e.find("byteLength");
    if (length != e.end() && length->is_number_unsigned()) out.buffers.emplace_back(p, length->get<std::uintmax_t>());
    else out.buffers.emplace_back(p, std::numeric_limits<std::uintmax_t>::max());  // (tinygltf refuses it)
  });
  each_file("images", [&](const fs::path& p, const nlohmann::json&) {
    if (std::none_of(out.buffers.begin(), out.buffers.end(), [&](const auto& b) { return b.first == p; })) out.images.push_back(p);
  });
  return out;
}

/// tinygltf's file access for the files a glTF names (external buffers and images), checked as the model file
/// is: only a regular file (a FIFO would block the open forever, a device never end), of at most
/// max_file_bytes, read no further than its size. Existence is asked without opening the file. With the
/// glTF's NamedFiles (user data), its images are not read, nor a buffer's file of another size than its
/// byteLength.
bool resource_exists(const std::string& path, void*) {
  std::error_code ec;
  return fs::exists(fs::status(path, ec));
}
bool read_resource(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  const auto* named = static_cast<const NamedFiles*>(user);
  const fs::path normal = fs::path(path).lexically_normal();
  if (named && std::find(named->images.begin(), named->images.end(), normal) != named->images.end()) {
    if (err) *err += path + ": an image (snh does not use images)\n";
    return false;
  }
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  std::string why;
  std::uintmax_t n = 0;
  if (!fs::exists(st)) why = "no such file";
  else if (!fs::is_regular_file(st)) why = fs::is_directory(st) ? "a directory" : "not a regular file (a FIFO, device or socket)";
  else if (n = fs::file_size(path, ec); ec) why = "cannot read its size";
  else if (n > rig_build::max_file_bytes) why = fmt::format("too large ({} bytes; at most {})", n, rig_build::max_file_bytes);
  else if (named) {
    std::uintmax_t expected = 0;
    bool is_buffer = false, fits = false;
    for (const auto& [p, length] : named->buffers)
      if (p == normal) is_buffer = true, expected = length, fits = fits || length == n;
    if (is_buffer && !fits && expected != std::numeric_limits<std::uintmax_t>::max())
      why = fmt::format("{} bytes, where the glTF's buffer says {} (byteLength)", n, expected);
  }
  if (why.empty()) {
    std::ifstream in(path, std::ios::binary);
    out->assign(static_cast<std::size_t>(n), 0);
    if (n > 0) in.read(reinterpret_cast<char*>(out->data()), static_cast<std::streamsize>(n));
    if (!in || static_cast<std::uintmax_t>(in.gcount()) != n) why = "cannot read it";
  }
  if (why.empty()) return true;
  if (err) *err += path + ": " + why + "\n";
  return false;
}
bool refuse_write(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "snh does not write glTF files\n";
  return false;
}

bool ignore_image(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;
}

constexpr std::size_t kMaxGltfDepth = 64;

}  // namespace

tinygltf::Model load(const fs::path& path) {
  std::size_t size = 0;
  const std::vector<unsigned char> bytes = read_file(path, size);
  const bool binary = size >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
  if (!binary) {  // (a .glb without the magic was refused by read_file)
    std::size_t i = size >= 3 && bytes[0] == 0xEF && bytes[1] == 0xBB && bytes[2] == 0xBF ? 3 : 0;  // UTF-8 BOM
    while (i < size && (bytes[i] == ' ' || bytes[i] == '\t' || bytes[i] == '\n' || bytes[i] == '\r')) ++i;
    if (i == size || bytes[i] != '{') fail(path, "not glTF (neither a glTF binary nor a JSON object)");
  }
  if (size > std::numeric_limits<unsigned int>::max()) fail(path, "too large for tinygltf");
  // tinygltf copies extras into nested values recursively: a file that nests thousands of arrays would
  // overflow the stack. A glTF's own structure is a few levels deep; extras get room to spare.
  std::string_view json_text(reinterpret_cast<const char*>(bytes.data()), size);
  if (binary && size >= 20) {  // the first chunk of a GLB is its JSON: 12-byte header, then length and type
    std::uint32_t length = 0;
    std::memcpy(&length, bytes.data() + 12, 4);
    json_text = json_text.substr(20, std::min<std::size_t>(length, size - 20));
  }
  if (json_depth(json_text, kMaxGltfDepth) > kMaxGltfDepth)
    fail(path, fmt::format("its JSON is nested deeper than {} levels (a glTF needs a handful)", kMaxGltfDepth));
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(&ignore_image, nullptr);
  const std::string base = path.parent_path().string();
  NamedFiles named = named_files(json_text, base);
  loader.SetFsCallbacks(tinygltf::FsCallbacks{&resource_exists, &tinygltf::ExpandFilePath, &read_resource, &refuse_write, &named});
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    if (binary)
      ok = loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), static_cast<unsigned int>(size), base);
    else
      ok = loader.LoadASCIIFromString(&model, &err, &warn, reinterpret_cast<const char*>(bytes.data()),
                                      static_cast<unsigned int>(size), base);
  } catch (const std::exception& e) {  // tinygltf indexes with .at() in places
    ok = false;
    err = e.what();
  }
  if (!ok) {
    std::string why = one_line(err.empty() ? warn : err);
    if (why.empty()) why = "tinygltf could not load it";
    fail(path, fmt::format("not a valid glTF {}: {}", binary ? "binary" : "file", why));
  }
  return model;
}

}  // namespace snh::gltf
