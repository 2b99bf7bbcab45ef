#include "snh/io/surface_read.hpp"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <map>
#include <random>
#include <string>
#include <vector>

#include "snh/io/lexer.hpp"

extern char** environ;

namespace snh {
namespace {

namespace fs = std::filesystem;
using detail::Lexer;
using detail::read_all;

/// Index i (0-based) as the messages number vertices, i + 1, without overflow where a file holds the largest
/// index there is (fuzzing found an OFF face with 9223372036854775807).
std::string one_based(long long i) {
  return i >= 0 ? fmt::format("{}", static_cast<unsigned long long>(i) + 1u) : fmt::format("{}", i + 1);
}

struct Collect {
  std::vector<double> xyz;
  std::vector<int> tri;
  /// A polygon (0-based indices) split into a fan; indices checked against the vertex count.
  void polygon(Lexer& lx, const std::vector<long long>& v, int line) {
    if (v.size() < 3) lx.fail(fmt::format("a face needs at least 3 vertices, got {}", v.size()), line);
    const long long n = static_cast<long long>(xyz.size() / 3);
    for (long long i : v)
      if (i < 0 || i >= n) lx.fail(fmt::format("face refers to vertex {}, but there are {}", one_based(i), n), line);
    for (std::size_t k = 1; k + 1 < v.size(); ++k)
      tri.insert(tri.end(), {static_cast<int>(v[0]), static_cast<int>(v[k]), static_cast<int>(v[k + 1])});
  }
  SurfaceMesh finish(const Lexer& lx) const {
    if (tri.empty()) lx.fail("the surface has no faces");
    SurfaceMesh s;
    s.vertices = Eigen::Map<const Eigen::Matrix3Xd>(xyz.data(), 3, static_cast<Eigen::Index>(xyz.size() / 3));
    s.triangles = Eigen::Map<const Eigen::Matrix3Xi>(tri.data(), 3, static_cast<Eigen::Index>(tri.size() / 3));
    return s;
  }
};

/// `count` faces of "k i0 … i(k−1)" (0-based) as in OFF and PLY; `rest_of_line`: skip what follows each
/// face on its line (OFF's optional colour).
void read_counted_faces(Lexer& lx, Collect& c, long long count, bool rest_of_line) {
  for (long long f = 0; f < count; ++f) {
    const long long k = lx.count("the vertices of a face", 1000);
    const int line = lx.line();
    std::vector<long long> v(k);
    for (auto& i : v) i = lx.integer("a vertex index");
    c.polygon(lx, v, line);
    if (rest_of_line) lx.skip_line();
  }
}

SurfaceMesh read_obj_surface(const fs::path& path) {
  Lexer file = Lexer::open(path, detail::text_head(path, '#'));
  Lexer err(path, "");
  Collect c;
  std::vector<double> vn;            // the "vn" lines' normals, 3 each
  std::vector<long long> normal_of;  // per corner read so far: its vertex and its normal (-1: none), in pairs
  int line_no = 0;
  // A corner's index (v, vt or vn: 1-based, negative relative to the `count` read so far) as 0-based.
  const auto index = [&](std::string_view text, std::string_view t, long long count) {
    long long i = 0;
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), i);
    if (ec != std::errc() || end != text.data() + text.size() || i == 0)
      err.fail(fmt::format("expected a vertex index, got '{}'", t), line_no);
    return i > 0 ? i - 1 : count + i;
  };
  for (std::string line; file.rest_of_line(line, line_no);) {
    Lexer lx(path, line, '#');
    const std::string_view tag = lx.next();
    if (tag == "v" || tag == "vn") {
      std::vector<double>& to = tag == "v" ? c.xyz : vn;
      try {
        for (int a = 0; a < 3; ++a) to.push_back(lx.number(tag == "v" ? "a coordinate" : "a normal's coordinate"));
      } catch (const MeshError& e) {
        const std::string what = e.what();
        err.fail(what.substr(what.find(": ", path.string().size()) + 2), line_no);
      }
    } else if (tag == "f") {
      std::vector<long long> v;
      for (std::string_view t = lx.next(); !t.empty(); t = lx.next()) {
        const std::size_t slash = t.find('/');
        v.push_back(index(t.substr(0, slash), t, static_cast<long long>(c.xyz.size() / 3)));
        // v//vn or v/vt/vn: the normal's index after the second slash.
        const std::size_t second = slash == std::string_view::npos ? slash : t.find('/', slash + 1);
        long long n = -1;
        if (second != std::string_view::npos) {
          const long long normals = static_cast<long long>(vn.size() / 3);
          n = index(t.substr(second + 1), t, normals);
          if (n < 0 || n >= normals) err.fail(fmt::format("face refers to normal {}, but there are {}", one_based(n), normals), line_no);
        }
        normal_of.insert(normal_of.end(), {v.back(), n});
      }
      c.polygon(err, v, line_no);
    }  // vt, o, g, s, usemtl, mtllib, l: not needed
  }
  SurfaceMesh s = c.finish(err);
  // Each vertex's normal: the first its corners name; none at all unless every vertex has one.
  const Eigen::Index nv = s.vertices.cols();
  Eigen::Matrix3Xd normals = Eigen::Matrix3Xd::Constant(3, nv, std::numeric_limits<double>::quiet_NaN());
  std::vector<char> has(static_cast<std::size_t>(nv), 0);
  for (std::size_t k = 0; k < normal_of.size(); k += 2) {
    const long long v = normal_of[k], n = normal_of[k + 1];
    if (n < 0 || has[static_cast<std::size_t>(v)]) continue;
    normals.col(v) = Eigen::Vector3d(vn[3 * n], vn[3 * n + 1], vn[3 * n + 2]);
    has[static_cast<std::size_t>(v)] = 1;
  }
  if (nv > 0 && std::all_of(has.begin(), has.end(), [](char h) { return h != 0; })) s.normals = std::move(normals);
  return s;
}

SurfaceMesh read_off(const fs::path& path) {
  Lexer lx = Lexer::open(path, detail::text_head(path, '#'), '#');
  const std::string_view magic = lx.word("OFF");
  Collect c;
  long long nv = 0;
  if (magic == "OFF") nv = lx.count("the number of vertices");
  else if (magic.substr(0, 3) == "OFF") {  // "OFF8 …" style: the counts follow on the same line
    lx.fail(fmt::format("unsupported OFF variant '{}'", magic));
  } else {
    lx.fail(fmt::format("not an OFF file: it starts with '{}'", magic));
  }
  const long long nf = lx.count("the number of faces");
  (void)lx.count("the number of edges");
  for (long long i = 0; i < nv; ++i)
    for (int a = 0; a < 3; ++a) c.xyz.push_back(lx.number("a coordinate"));
  read_counted_faces(lx, c, nf, true);
  detail::expect_file_end(lx, "the faces the header announces");
  return c.finish(lx);
}

SurfaceMesh read_ply(const fs::path& path) {
  Lexer lx = Lexer::open(path, detail::text_head(path, '\0'));
  if (lx.word("ply") != "ply") lx.fail("not a PLY file: it must start with 'ply'");
  long long nv = -1, nf = -1;
  std::vector<std::string> vertex_props;
  std::string current;
  for (;;) {
    const std::string_view t = lx.word("end_header");
    if (t == "end_header") break;
    if (t == "format") {
      const std::string_view f = lx.word("the format");
      if (f != "ascii") lx.fail(fmt::format("PLY format '{}' is not supported (ascii is)", f));
      (void)lx.word("the version");
    } else if (t == "comment" || t == "obj_info") {
      lx.skip_line();
    } else if (t == "element") {
      current = std::string(lx.word("an element name"));
      const long long n = lx.count("the element count");
      if (current == "vertex") nv = n;
      else if (current == "face") nf = n;
      else if (n > 0) lx.fail(fmt::format("PLY element '{}' is not supported", current));
    } else if (t == "property") {
      const std::string_view type = lx.word("a property type");
      if (type == "list") {
        (void)lx.word("the list count type");
        (void)lx.word("the list item type");
        const std::string_view name = lx.word("a property name");
        if (current != "face" || (name != "vertex_indices" && name != "vertex_index"))
          lx.fail(fmt::format("unsupported list property '{}'", name));
      } else {
        const std::string_view name = lx.word("a property name");
        if (current == "vertex") vertex_props.emplace_back(name);
        else if (current == "face") lx.fail("face properties other than the vertex list are not supported");
      }
    } else {
      lx.fail(fmt::format("unexpected '{}' in the PLY header", t));
    }
  }
  if (nv < 0 || nf < 0) lx.fail("the header needs 'element vertex' and 'element face'");
  int ix = -1, iy = -1, iz = -1;
  for (int p = 0; p < static_cast<int>(vertex_props.size()); ++p) {
    if (vertex_props[p] == "x") ix = p;
    if (vertex_props[p] == "y") iy = p;
    if (vertex_props[p] == "z") iz = p;
  }
  if (ix < 0 || iy < 0 || iz < 0) lx.fail("the vertices need x, y and z properties");
  Collect c;
  std::vector<double> row(vertex_props.size());
  for (long long i = 0; i < nv; ++i) {
    for (auto& r : row) r = lx.number("a vertex property");
    c.xyz.insert(c.xyz.end(), {row[ix], row[iy], row[iz]});
  }
  read_counted_faces(lx, c, nf, false);
  if (!lx.at_end()) lx.fail("more data than the header announces");
  return c.finish(lx);
}

SurfaceMesh read_stl(const fs::path& path) {
  Collect c;
  std::map<std::array<double, 3>, int> index;  // STL repeats corners: merge identical ones
  auto corner = [&](const std::array<double, 3>& p) {
    const auto [it, inserted] = index.emplace(p, static_cast<int>(c.xyz.size() / 3));
    if (inserted) c.xyz.insert(c.xyz.end(), p.begin(), p.end());
    return static_cast<long long>(it->second);
  };
  Lexer err(path, "");
  // Binary: an 80-byte header, a count, 50 bytes per triangle; the size must match exactly. Which of the
  // two it is follows from the first 84 bytes and the size, before the rest is read.
  std::uintmax_t size = 0;
  if (const std::string problem = input_file_problem(path, "mesh file", &size); !problem.empty()) throw MeshError(problem);
  const std::string head = read_head(path, 84);
  std::uint32_t n = 0;
  if (head.size() == 84) std::memcpy(&n, head.data() + 80, 4);
  if (head.size() == 84 && size == 84 + 50ULL * n) {
    const std::string bytes = read_all(path);
    if (bytes.size() != size) err.fail("the file changed while it was read", 0);
    for (std::uint32_t t = 0; t < n; ++t) {
      std::vector<long long> v;
      for (int k = 0; k < 3; ++k) {
        float p[3];
        std::memcpy(p, bytes.data() + 84 + 50ULL * t + 12 + 12 * k, 12);
        if (!std::isfinite(p[0]) || !std::isfinite(p[1]) || !std::isfinite(p[2]))
          err.fail(fmt::format("triangle {} has a non-finite coordinate", t), 0);
        v.push_back(corner({p[0], p[1], p[2]}));
      }
      c.polygon(err, v, 0);
    }
    return c.finish(err);
  }
  // ASCII: its first word is "solid", else it is neither.
  Lexer lx = Lexer::open(path, [&](const std::string& first) {
    const std::size_t at = first.find_first_not_of(" \t\r\n");
    if (at != std::string::npos && first.compare(at, 5, "solid") == 0 &&
        (first.size() == at + 5 || std::isspace(static_cast<unsigned char>(first[at + 5]))))
      return;
    const Lexer h(path, "");
    if (first.size() < 84)
      h.fail(fmt::format("not an STL file: it does not start with 'solid' (ASCII) and its {} bytes are fewer than a binary STL's 84", size), 1);
    h.fail(fmt::format("not an STL file: it does not start with 'solid' (ASCII), and as binary STL its count of {} triangles needs "
                       "84 + 50 x {} = {} bytes, not {}",
                       n, n, 84 + 50ULL * n, size),
           1);
  });
  (void)lx.word("solid");
  lx.skip_line();
  for (;;) {
    const std::string_view t = lx.word("facet or endsolid");
    if (t == "endsolid") {
      lx.skip_line();  // the solid's name
      detail::expect_file_end(lx, "endsolid");
      break;
    }
    if (t != "facet") lx.fail(fmt::format("expected 'facet', got '{}'", t));
    lx.skip_line();  // normal
    if (lx.word("outer") != "outer" || lx.word("loop") != "loop") lx.fail("expected 'outer loop'");
    const int line = lx.line();
    std::vector<long long> v;
    for (int k = 0; k < 3; ++k) {
      if (lx.word("vertex") != "vertex") lx.fail("expected 'vertex'");
      const double x = lx.number("x"), y = lx.number("y"), z = lx.number("z");
      v.push_back(corner({x, y, z}));
    }
    if (lx.word("endloop") != "endloop" || lx.word("endfacet") != "endfacet") lx.fail("expected 'endloop endfacet'");
    c.polygon(lx, v, line);
  }
  return c.finish(lx);
}

/// The absolute path of `program` on PATH, or empty.
fs::path find_program(const std::string& program) {
  const char* path = std::getenv("PATH");
  std::string_view rest = path ? path : "/usr/bin:/bin";
  while (!rest.empty()) {
    const std::size_t colon = rest.find(':');
    const fs::path candidate = fs::path(std::string(rest.substr(0, colon))) / program;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    if (colon == std::string_view::npos) break;
    rest.remove_prefix(colon + 1);
  }
  return {};
}

}  // namespace

bool is_surface_file(const fs::path& path) {
  const std::string ext = path.extension().string();
  return ext == ".obj" || ext == ".off" || ext == ".ply" || ext == ".stl";
}

SurfaceMesh read_surface(const fs::path& path) {
  const std::string ext = path.extension().string();
  if (ext == ".obj") return read_obj_surface(path);
  if (ext == ".off") return read_off(path);
  if (ext == ".ply") return read_ply(path);
  if (ext == ".stl") return read_stl(path);
  throw MeshError(fmt::format("{}: unknown surface format '{}' (known: .obj, .off, .ply, .stl)", path.string(), ext));
}

MeshFile tetrahedralize(const SurfaceMesh& surface, const fs::path& source, double max_volume) {
  const fs::path tetgen = find_program("tetgen");
  if (tetgen.empty())
    throw MeshError(fmt::format("{}: a surface mesh is tetrahedralized by the tetgen program, which is not installed "
                                "(Debian package tetgen: apt-get install tetgen)",
                                source.string()));
  // A private temporary directory for the program's input and output.
  std::string dir_template = (fs::temp_directory_path() / "snh-tetgen-XXXXXX").string();
  if (!::mkdtemp(dir_template.data())) throw MeshError(fmt::format("{}: cannot create a temporary directory", source.string()));
  const fs::path dir = dir_template;
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{dir};
  {
    std::ofstream off(dir / "surface.off");
    off << "OFF\n" << surface.vertices.cols() << ' ' << surface.triangles.cols() << " 0\n";
    for (Eigen::Index v = 0; v < surface.vertices.cols(); ++v)
      off << fmt::format("{:.17g} {:.17g} {:.17g}\n", surface.vertices(0, v), surface.vertices(1, v), surface.vertices(2, v));
    for (Eigen::Index t = 0; t < surface.triangles.cols(); ++t)
      off << fmt::format("3 {} {} {}\n", surface.triangles(0, t), surface.triangles(1, t), surface.triangles(2, t));
    if (!off) throw MeshError(fmt::format("{}: cannot write the temporary surface for tetgen", source.string()));
  }
  const std::string program = tetgen.string(), switches = max_volume > 0.0 ? fmt::format("-pq1.414a{:.6g}Q", max_volume) : "-pq1.414Q", input = (dir / "surface.off").string(),
                    log = (dir / "tetgen.log").string();
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  std::vector<char*> argv = {const_cast<char*>(program.c_str()), const_cast<char*>(switches.c_str()),
                             const_cast<char*>(input.c_str()), nullptr};
  pid_t pid = 0;
  const int spawned = posix_spawn(&pid, program.c_str(), &actions, nullptr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (spawned != 0) throw MeshError(fmt::format("{}: cannot run {}", source.string(), program));
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  const fs::path node = dir / "surface.1.node";
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !fs::exists(node)) {
    std::ifstream in(log);
    std::string last, line;
    while (std::getline(in, line))
      if (!line.empty()) last = line;
    // TetGen's own last line says why; a crash (a C++ runtime's "terminate called after throwing an instance
    // of 'int'", then SIGABRT) says nothing to a user: the signal is named instead.
    std::string why = last.rfind("terminate called", 0) == 0 ? std::string() : last;
    if (WIFSIGNALED(status)) why = fmt::format("tetgen crashed ({})", ::strsignal(WTERMSIG(status)));
    throw MeshError(fmt::format("{}: tetgen could not tetrahedralize the surface (is it closed and not self-intersecting?){}",
                                source.string(), why.empty() ? "" : ": " + why));
  }
  MeshFile m = read_mesh_file(node);
  // The cells' lines are lines of tetgen's temporary .ele file, not of `source`: the messages name cells only.
  m.cell_lines.clear();
  m.cell_tags.clear();  // tetgen's regions, not the surface's
  check_mesh(m, source.string() + " (tetrahedralized by tetgen)");
  return m;
}

}  // namespace snh
