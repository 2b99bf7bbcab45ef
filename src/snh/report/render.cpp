#include "snh/report/render.hpp"

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <functional>
#include <optional>
#include <sstream>
#include <string_view>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/atomic_file.hpp"
#include "snh/io/base64.hpp"
#include "snh/io/mesh_read.hpp"
#include "snh/io/surface_read.hpp"
#include "snh/io/vtu.hpp"
#include "snh/report/browser.hpp"
#include "snh/report/report.hpp"
#include "snh/run/interrupt.hpp"

extern char** environ;

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

/// `name` found on PATH ("" if not there); a name with a slash is returned as it is.
std::string on_path(const std::string& name) {
  if (name.find('/') != std::string::npos) return name;
  const char* path = std::getenv("PATH");
  std::stringstream dirs(path ? path : "/usr/bin:/bin");
  for (std::string d; std::getline(dirs, d, ':');) {
    const fs::path candidate = fs::path(d.empty() ? "." : d) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
  }
  return "";
}

/// The browser to use: the option, $SNH_CHROMIUM (either a path or a name on PATH), or the first of the
/// usual names on PATH. "" when none is found.
std::string find_browser(const std::string& given) {
  if (!given.empty()) return on_path(given).empty() ? given : on_path(given);
  if (const char* env = std::getenv("SNH_CHROMIUM"); env && *env) return on_path(env).empty() ? env : on_path(env);
  for (const char* name : {"chromium", "chromium-browser", "google-chrome", "google-chrome-stable"})
    if (const std::string found = on_path(name); !found.empty()) return found;
  return "";
}

/// A file:// URL of an absolute path: every byte but the unreserved characters and '/' percent-encoded
/// (a '#', '%' or '?' in a directory name would otherwise end or change the path).
std::string file_url(const fs::path& absolute) {
  std::string out = "file://";
  for (unsigned char c : absolute.string()) {
    if (std::isalnum(c) || c == '/' || c == '-' || c == '.' || c == '_' || c == '~') out += static_cast<char>(c);
    else out += fmt::format("%{:02X}", c);
  }
  return out;
}

/// A temporary directory for the browser's profile and log, removed (whatever is in it) when this goes out
/// of scope.
struct TempDir {
  fs::path path;
  TempDir() {
    std::error_code ec;
    const fs::path base = fs::temp_directory_path(ec);
    if (ec) throw WriteError(fmt::format("no temporary directory for the browser: {}", ec.message()));
    std::string templ = (base / "snh-render-XXXXXX").string();
    if (!::mkdtemp(templ.data()))
      throw WriteError(fmt::format("cannot create a temporary directory in {}: {}", base.string(), std::strerror(errno)));
    path = templ;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
};

/// Refuses an output path that is a directory or another file that is not a regular one (a device, a FIFO,
/// a socket: the rename that writes the picture would replace it), and one in a missing directory.
void check_output_path(const fs::path& out) {
  std::error_code ec;
  const fs::file_status st = fs::status(out, ec);  // through a symbolic link
  if (fs::is_directory(st))
    throw ReportError(fmt::format("{}: is a directory (--out takes the PNG file to write)", out.string()));
  check_replaceable(out);  // a FIFO, a device, a socket: OutputRefused, as for every writer
  if (out.has_parent_path() && !fs::is_directory(out.parent_path(), ec))
    throw ReportError(fmt::format("{}: the directory does not exist", out.parent_path().string()));
}

/// The page's title once it drew the frame, and the start of its title when it could not (then followed
/// by why): set by viewer/src/main.js in render mode.
constexpr std::string_view kReady = "snh-render-ready", kFailed = "snh-render-error: ";

/// Waits, in real time, until the report page's title is kReady or starts with kFailed, and gives it.
constexpr const char* kAwaitTitle = R"(new Promise((resolve) => {
  const look = () => {
    const t = document.title;
    if (t === 'snh-render-ready' || t.startsWith('snh-render-error: ')) resolve(t);
    else setTimeout(look, 20);
  };
  look();
}))";

/// The PNG bytes of the page's view now.
std::string capture(HeadlessBrowser& chromium, const std::string& page) {
  const json shot = chromium.call("Page.captureScreenshot", {{"format", "png"}}, page);
  std::string png;
  if (!base64_decode(shot.value("data", std::string()), png)) throw BrowserError("the browser's picture is not valid base64");
  return png;
}

/// Opens `url` in a fresh headless browser (its profile, log and temporary files in `work`) with a
/// width by height view, waits until the page has drawn the frame (or reported why not), then calls
/// `shoot(browser, page session)`. The browser is stopped when this returns or throws; every wait ends
/// `timeout_seconds` after the start.
void session(const std::string& browser, const std::string& url, const RenderOptions& o, const fs::path& work,
             double timeout_seconds, const std::function<void(HeadlessBrowser&, const std::string&)>& shoot) {
  const std::vector<std::string> flags = {
      "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--disable-quic", "--no-first-run", "--no-startup-window",
      "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-extensions",
      "--mute-audio", "--user-data-dir=" + (work / "profile").string(),
      fmt::format("--window-size={},{}", o.width, o.height)};
  const fs::path temp = work / "tmp";
  std::error_code ec;
  if (!fs::create_directory(temp, ec))
    throw WriteError(fmt::format("cannot create {}: {}", temp.string(), ec ? ec.message() : "it exists"));
  HeadlessBrowser chromium(browser, flags, work / "browser.log", temp, timeout_seconds);
  const json target = chromium.call("Target.createTarget", {{"url", "about:blank"}});
  const std::string page =
      chromium.call("Target.attachToTarget", {{"targetId", target.at("targetId")}, {"flatten", true}}).at("sessionId");
  chromium.call("Emulation.setDeviceMetricsOverride",
                {{"width", o.width}, {"height", o.height}, {"deviceScaleFactor", 1}, {"mobile", false}}, page);
  chromium.call("Inspector.enable", json::object(), page);  // reports a crash of the page
  chromium.call("Page.enable", json::object(), page);
  chromium.call("Page.setLifecycleEventsEnabled", {{"enabled", true}}, page);
  const json navigation = chromium.call("Page.navigate", {{"url", url}}, page);
  if (navigation.contains("errorText"))
    throw BrowserError(fmt::format("the browser could not open {}: {}", url, navigation["errorText"].get<std::string>()));
  // The report's own load event (not one of the blank page it replaces): its scripts have run, and the
  // page now loads the frame and draws it.
  const json loader = navigation.value("loaderId", json());
  chromium.wait_for_event("Page.lifecycleEvent", page, [&](const json& p) {
    return p.value("name", std::string()) == "load" && p.value("loaderId", json()) == loader;
  });
  const json title =
      chromium.call("Runtime.evaluate", {{"expression", kAwaitTitle}, {"awaitPromise", true}, {"returnByValue", true}}, page);
  const json said = title.contains("exceptionDetails") ? json() : title.at("result").value("value", json());
  if (!said.is_string()) throw BrowserError("the report page could not be watched: " + title.dump());
  const std::string text = said.get<std::string>();
  if (text != kReady) throw BrowserError("the report page: " + text.substr(kFailed.size()));
  shoot(chromium, page);
}

/// Width and height of PNG bytes from their header; {0, 0} if they are not a PNG.
std::pair<int, int> png_header_size(std::string_view head) {
  if (head.size() < 24 || head.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 || head.compare(12, 4, "IHDR") != 0) return {0, 0};
  auto be32 = [&](std::size_t at) {
    return (static_cast<unsigned char>(head[at]) << 24) | (static_cast<unsigned char>(head[at + 1]) << 16) |
           (static_cast<unsigned char>(head[at + 2]) << 8) | static_cast<unsigned char>(head[at + 3]);
  };
  return {be32(16), be32(20)};
}

/// The camera's named views (viewer/src/camera.js VIEWS).
constexpr std::string_view kViews[] = {"three-quarter", "front", "back", "left", "right", "top"};

/// Whether the viewer script that DIR/index.html loads (report/snh-report.js, or a lab's shared copy
/// further up) is this build's.
bool current_viewer(const fs::path& dir) {
  std::ifstream page(dir / "index.html");
  std::string html(4096, '\0');  // the script tags come first
  page.read(html.data(), static_cast<std::streamsize>(html.size()));
  html.resize(static_cast<std::size_t>(page.gcount()));
  const std::size_t end = html.find("snh-report.js\"");
  const std::size_t start = end == std::string::npos ? end : html.rfind('"', end);
  if (start == std::string::npos) return false;
  const fs::path script = dir / html.substr(start + 1, end + std::string_view("snh-report.js").size() - start - 1);
  const std::string_view bundle = report_bundle();
  std::error_code ec;
  if (fs::file_size(script, ec) != bundle.size() || ec) return false;
  std::ifstream in(script, std::ios::binary);
  std::string text(bundle.size(), '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  return in.gcount() == static_cast<std::streamsize>(text.size()) && text == bundle;
}

/// --show's list: one to four of flesh, lbs, difference and volume, comma-separated ("" → none given).
std::vector<std::string> split_show(const std::string& show) {
  std::vector<std::string> out;
  if (show.empty()) return out;
  std::size_t at = 0;
  while (true) {
    const std::size_t comma = show.find(',', at);
    const std::string part = show.substr(at, comma == std::string::npos ? std::string::npos : comma - at);
    if (part != "flesh" && part != "lbs" && part != "difference" && part != "volume")
      throw ReportError(fmt::format("--show {}: expected flesh, lbs, difference or volume, or up to four of them "
                                    "comma-separated (side by side), got '{}'", show, part));
    out.push_back(part);
    if (comma == std::string::npos) break;
    at = comma + 1;
  }
  if (out.size() > 4) throw ReportError(fmt::format("--show {}: at most four side by side", show));
  return out;
}

/// Refuses a --focus that names no joint of the run's bones ("head>tail" names, or one name for an end).
void check_joint(const json& render, const std::string& joint) {
  std::vector<std::string> joints;
  if (render.contains("bones") && render.at("bones").is_array())
    for (const json& b : render.at("bones")) {
      const std::string name = b.is_string() ? b.get<std::string>() : std::string();
      for (std::size_t at = 0; at <= name.size();) {
        const std::size_t gt = std::min(name.find('>', at), name.size());
        const std::string j = name.substr(at, gt - at);
        if (!j.empty() && std::find(joints.begin(), joints.end(), j) == joints.end()) joints.push_back(j);
        at = gt + 1;
      }
    }
  if (std::find(joints.begin(), joints.end(), joint) != joints.end()) return;
  if (joints.empty()) throw ReportError(fmt::format("--focus {}: the run has no bones (no bones.json)", joint));
  std::string list;
  for (std::size_t k = 0; k < joints.size() && k < 12; ++k) list += (k ? ", " : "") + joints[k];
  if (joints.size() > 12) list += fmt::format(", … ({} in all)", joints.size());
  throw ReportError(fmt::format("--focus {}: no joint of that name (the run's joints: {})", joint, list));
}

/// Text for a URL's fragment: every byte but the unreserved characters percent-encoded.
std::string url_component(const std::string& text) {
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '.' || c == '_' || c == '~') out += static_cast<char>(c);
    else out += fmt::format("%{:02X}", c);
  }
  return out;
}

}  // namespace

std::pair<int, int> png_size(const fs::path& png) {
  std::ifstream in(png, std::ios::binary);
  char head[24] = {};
  in.read(head, sizeof head);
  return png_header_size(std::string_view(head, static_cast<std::size_t>(in.gcount())));
}

namespace {

/// What the checks of a render found: the browser, the page's address (all but the frame), the frame a
/// picture shows and the times of the run's frames.
struct Plan {
  std::string browser, url;
  int frame = 0;              ///< a picture's frame (a video's: 0)
  std::vector<double> times;  ///< of every frame of the run
  /// The page's address showing frame `i` first.
  [[nodiscard]] std::string at(int i) const { return fmt::format("{}&frame={}", url, i); }
};

/// Checks the options against the run in `dir` (writing its report first if it has none) and the browser,
/// each failure one line: ReportError for a bad argument, BrowserError for a missing browser.
Plan plan_render(const fs::path& dir, const RenderOptions& o, const fs::path& out, bool video) {
  if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192)
    throw ReportError(fmt::format("the picture size must be from 16 to 8192 pixels each way, got {}x{}", o.width, o.height));
  check_output_path(out);
  const std::vector<std::string> shows = split_show(o.show);
  if (!o.view.empty() && std::find(std::begin(kViews), std::end(kViews), o.view) == std::end(kViews))
    throw ReportError(fmt::format("--view {}: expected three-quarter, front, back, left, right or top", o.view));
  if (!o.range.empty() && o.range != "run" && o.range != "frame") {
    // LO:HI, two finite numbers, LO below HI.
    const std::size_t colon = o.range.find(':');
    double lo = NAN, hi = NAN;
    const auto number = [](const std::string& t, double& v) {
      const auto [end, ec] = std::from_chars(t.data(), t.data() + t.size(), v);
      return ec == std::errc() && end == t.data() + t.size() && std::isfinite(v);
    };
    if (colon == std::string::npos || !number(o.range.substr(0, colon), lo) || !number(o.range.substr(colon + 1), hi) || !(lo < hi))
      throw ReportError(fmt::format("--range {}: expected run (the whole run's distances), frame (the frame's own) or LO:HI "
                                    "in millimetres with LO below HI", o.range));
  }
  if (!o.fit.empty() && o.fit != "frame" && o.fit != "animation")
    throw ReportError(fmt::format("--fit {}: expected frame (the frame shown fills the picture) or animation (every frame would fit)", o.fit));
  // A report written by another build of snh has another viewer, which may not know the options asked for
  // (and data without what they need): such a report is written again first, as a missing one is.
  if (!fs::exists(dir / "index.html") || !fs::exists(dir / "report" / "data.js") || !current_viewer(dir))
    (void)write_report(dir);
  // The frame and field are checked here, so that the page is only asked for what it has.
  const json data = read_report_data(dir);
  if (!data.contains("mesh") || data.at("mesh").is_null())
    throw ReportError(fmt::format("{}: the run has no 3D frames to render (no frames.pvd)", dir.string()));
  const json& mesh = data.at("mesh");
  Plan plan;
  for (const json& f : mesh.at("frames")) plan.times.push_back(f.contains("time") && f.at("time").is_number() ? f.at("time").get<double>() : NAN);
  const int frames = static_cast<int>(plan.times.size());
  const int frame = video ? 0 : o.frame < 0 ? frames - 1 : o.frame;
  if (frame >= frames)
    throw ReportError(fmt::format("frame {} does not exist: {} has frames 0 to {}", o.frame, dir.string(), frames - 1));
  std::string field = o.field.empty() ? mesh.value("default_field", std::string("J")) : o.field;
  std::string known;
  bool found = false;
  for (const json& f : mesh.at("fields")) {
    known += (known.empty() ? "" : ", ") + f.value("name", std::string());
    found = found || f.value("name", std::string()) == field;
  }
  if (!found) throw ReportError(fmt::format("unknown field '{}' (this run has: {})", field, known));
  const bool flesh = data.contains("render") && !data.at("render").is_null();
  if (!flesh) {
    const char* given = !o.show.empty() ? "--show" : !o.focus.empty() ? "--focus" : o.bones ? "--bones" : !o.range.empty() ? "--range" : nullptr;
    if (given) throw ReportError(fmt::format("{}: {} is not a flesh run (it has no render surface)", given, dir.string()));
  } else {
    const json& render = data.at("render");
    if (std::find(shows.begin(), shows.end(), "difference") != shows.end() && !render.contains("distance"))
      throw ReportError(fmt::format("--show difference: the report of {} has no flesh–LBS distances (an older snh wrote it): run "
                                    "snh report {} first", dir.string(), dir.string()));
    if (!o.focus.empty()) check_joint(render, o.focus);
  }

  plan.browser = find_browser(o.browser);
  if (plan.browser.empty())
    throw BrowserError("snh render needs Chromium, and none was found on PATH: install the Debian package chromium "
                       "(apt-get install chromium), or set SNH_CHROMIUM to a Chromium or Chrome binary");
  if (::access(plan.browser.c_str(), X_OK) != 0)
    throw ReportError(fmt::format("the browser {} cannot be run (from SNH_CHROMIUM or --browser)", plan.browser));
  const std::string show = o.show.empty() && !o.compare.empty() ? "flesh,lbs" : o.show;  // two runs: side by side
  plan.frame = frame;
  plan.url = fmt::format("{}#render&field={}{}{}", file_url(fs::absolute(dir / "index.html")), field,
                         o.wireframe ? "&wireframe=1" : "", show.empty() ? "" : "&show=" + show);
  if (flesh) plan.url += o.bones ? "&bones=1" : "&bones=0";
  if (!o.view.empty()) plan.url += "&view=" + o.view;
  const std::string fit = !o.fit.empty() ? o.fit : video ? "animation" : "";  // a video's camera holds still
  if (!fit.empty()) plan.url += "&fit=" + fit;
  if (!o.focus.empty()) plan.url += "&focus=" + url_component(o.focus);
  if (!o.range.empty()) plan.url += "&range=" + url_component(o.range);
  return plan;
}

/// Refuses PNG bytes that are not a picture of the size asked for.
void check_png(const std::string& png, const RenderOptions& o) {
  const auto [w, h] = png_header_size(png);
  if (w != o.width || h != o.height)
    throw BrowserError(w == 0 ? std::string("the browser's picture is not a PNG")
                              : fmt::format("the browser's picture is {}x{}, not {}x{}", w, h, o.width, o.height));
}

/// Runs `argv` (found on PATH) with its output in `log` and waits for it, stopping it at a stop request
/// (then BrowserInterrupted); the exit status, or 128 + the signal that ended it.
int run_program(const std::vector<std::string>& argv, const fs::path& log) {
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setpgroup(&attr, 0);  // its own group: a Ctrl-C at the terminal reaches us, and we stop it
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  pid_t pid = -1;
  const int err = ::posix_spawnp(&pid, args[0], &actions, &attr, args.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (err != 0) throw EncoderError(fmt::format("{} could not be started: {}", argv[0], std::strerror(err)));
  int status = 0;
  while (::waitpid(pid, &status, WNOHANG) == 0) {
    if (stop_requested()) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw BrowserInterrupted(stop_signal());
    }
    ::usleep(20000);
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// The last line of a program's log that says something ("" when none does).
std::string last_line(const fs::path& log) {
  std::ifstream in(log);
  std::string line, last;
  while (std::getline(in, line))
    if (line.find_first_not_of(" \t\r") != std::string::npos) last = line;
  return last;
}

}  // namespace

fs::path comparison_run(const fs::path& dir, const fs::path& other, const fs::path& into) {
  // Both flesh runs of one skin, with as many frames.
  for (const fs::path& d : {dir, other}) {
    if (!fs::is_directory(d)) throw ReportError(fmt::format("--compare: {}: not a run's directory", d.string()));
    if (!fs::exists(d / "surface" / "000.obj") || !fs::exists(d / "frames.pvd"))
      throw ReportError(fmt::format("--compare: {} is not a flesh run (it has no surface/000.obj or frames.pvd)", d.string()));
  }
  const auto skin = [](const fs::path& d) {
    try {
      return read_surface(d / "surface" / "000.obj");
    } catch (const MeshError& e) {
      throw ReportError(e.what());
    }
  };
  const SurfaceMesh a = skin(dir), b = skin(other);
  if (a.vertices.cols() != b.vertices.cols() || a.triangles.cols() != b.triangles.cols() || a.triangles != b.triangles)
    throw ReportError(fmt::format("--compare: the skin of {} has {} vertices and {} triangles, that of {} {} and {}: runs of one "
                                  "model are compared", other.string(), b.vertices.cols(), b.triangles.cols(), dir.string(),
                                  a.vertices.cols(), a.triangles.cols()));
  const auto frames = [](const fs::path& d) {
    try {
      return read_pvd(d / "frames.pvd").size();
    } catch (const MeshError& e) {
      throw ReportError(e.what());
    }
  };
  if (frames(dir) != frames(other))
    throw ReportError(fmt::format("--compare: {} has {} frames, {} has {}: runs of one animation at one frame rate are compared",
                                  other.string(), frames(other), dir.string(), frames(dir)));
  // The run's own files, linked, and the other run's skin in place of the skinned one.
  const fs::path run = into / "comparison";
  fs::create_directories(run);
  for (const fs::directory_entry& e : fs::directory_iterator(dir)) {
    const std::string name = e.path().filename().string();
    if (name == "lbs" || name == "report" || name == "index.html") continue;
    fs::create_symlink(fs::absolute(e.path()), run / name);
  }
  fs::create_symlink(fs::absolute(other / "surface"), run / "lbs");
  (void)write_report(run);
  // Named by their directories (their whole paths where the names are alike).
  std::string mine = fs::absolute(dir).lexically_normal().filename().string(), theirs = fs::absolute(other).lexically_normal().filename().string();
  if (mine == theirs || mine.empty() || theirs.empty()) {
    mine = fs::absolute(dir).lexically_normal().string();
    theirs = fs::absolute(other).lexically_normal().string();
  }
  json data = read_report_data(run);
  data["render"]["labels"] = {{"flesh", mine}, {"lbs", theirs}, {"difference", fmt::format("{} − {} distance", mine, theirs)}};
  data["render"]["distance"]["label"] = fmt::format("distance from {}'s skin (mm)", theirs);
  data["title"] = fmt::format("{} against {}", mine, theirs);
  write_atomically(run / "report" / "data.js", [&](std::ostream& o) { o << "window.SNH_REPORT = " << data.dump() << ";\n"; });
  return run;
}

void render_png(const fs::path& dir, const RenderOptions& o) {
  if (o.out.empty()) throw ReportError("no output file given");
  const fs::path out = fs::absolute(o.out);
  std::optional<TempDir> pair;  // --compare: the two runs as one report
  const fs::path source = o.compare.empty() ? dir : comparison_run(dir, o.compare, pair.emplace().path);
  const Plan plan = plan_render(source, o, out, false);
  // The browser is driven over its DevTools pipe, in real time: the picture is taken once the page says
  // it drew the frame, however long that takes (within the timeout). Every wait in here is interrupted by
  // a stop signal, after which the browser is killed and its directory removed before this returns, so a
  // second signal waits for that instead of ending the process at once.
  std::string png;
  {
    PromptStopScope prompt;
    if (stop_requested()) throw BrowserInterrupted(stop_signal());
    TempDir work;
    session(plan.browser, plan.at(plan.frame), o, work.path, o.timeout_seconds,
            [&](HeadlessBrowser& chromium, const std::string& page) { png = capture(chromium, page); });
  }
  if (stop_requested()) throw BrowserInterrupted(stop_signal());
  check_png(png, o);
  write_atomically(out, [&](std::ostream& file) { file.write(png.data(), static_cast<std::streamsize>(png.size())); });
}

VideoSummary render_video(const fs::path& dir, const RenderOptions& o) {
  if (o.video.empty()) throw ReportError("no video file given");
  const fs::path out = fs::absolute(o.video);
  const std::string ext = out.extension().string();
  if (ext != ".mp4" && ext != ".gif")
    throw ReportError(fmt::format("{}: a video is .mp4 (H.264) or .gif (for web pages)", out.string()));
  if (ext == ".mp4" && (o.width % 2 != 0 || o.height % 2 != 0))
    throw ReportError(fmt::format("an .mp4 video needs an even width and height (H.264 in 4:2:0), got {}x{}", o.width, o.height));
  if (o.frame >= 0) throw ReportError("--frame picks a picture's frame; a video takes --frames FIRST:LAST");
  if (!(o.fps >= 0.0) || !std::isfinite(o.fps) || o.fps > 1000.0)
    throw ReportError(fmt::format("--fps must be a number from 0 (the run's own rate) to 1000, got {}", o.fps));
  std::optional<TempDir> pair;  // --compare: the two runs as one report
  const fs::path source = o.compare.empty() ? dir : comparison_run(dir, o.compare, pair.emplace().path);
  const Plan plan = plan_render(source, o, out, true);
  const int count = static_cast<int>(plan.times.size());
  // The frames: FIRST:LAST (either may be left out), all by default.
  int first = 0, last = count - 1;
  if (!o.frames.empty()) {
    const std::size_t colon = o.frames.find(':');
    const auto number = [&](const std::string& text, int fallback) {
      if (text.empty()) return fallback;
      int v = -1;
      const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
      if (ec != std::errc() || end != text.data() + text.size() || v < 0)
        throw ReportError(fmt::format("--frames {}: expected FIRST:LAST, frame numbers from 0 to {}", o.frames, count - 1));
      return v;
    };
    if (colon == std::string::npos) throw ReportError(fmt::format("--frames {}: expected FIRST:LAST (e.g. 0:24, or 12: to the end)", o.frames));
    first = number(o.frames.substr(0, colon), 0);
    last = number(o.frames.substr(colon + 1), count - 1);
    if (first > last || last >= count)
      throw ReportError(fmt::format("--frames {}: {} has frames 0 to {}", o.frames, dir.string(), count - 1));
  }
  // The run's rate: frames over the time they span (the scenes' frames are evenly spaced).
  double fps = o.fps;
  if (fps == 0.0) {
    const double span = plan.times[static_cast<std::size_t>(count - 1)] - plan.times[0];
    fps = count > 1 && span > 0.0 && std::isfinite(span) ? (count - 1) / span : 0.0;
    if (!(fps >= 0.1 && fps <= 1000.0)) fps = 10.0;  // steps without a time (snh stretch): ten a second
  }
  {
    PromptStopScope prompt;
    if (stop_requested()) throw BrowserInterrupted(stop_signal());
    TempDir work;
    // Each frame drawn and taken in one browser, into numbered PNG files; then ffmpeg makes the video of them.
    session(plan.browser, plan.at(first), o, work.path, o.timeout_seconds + 10.0 * (last - first + 1),
            [&](HeadlessBrowser& chromium, const std::string& page) {
              for (int i = first; i <= last; ++i) {
                const json r = chromium.call(
                    "Runtime.evaluate",
                    {{"expression", fmt::format("window.snhReport.setFrame({}).then(() => document.title)", i)},
                     {"awaitPromise", true}, {"returnByValue", true}}, page);
                if (r.contains("exceptionDetails"))
                  throw BrowserError(fmt::format("the report page could not show frame {}: {}", i, r.at("exceptionDetails").value("text", std::string())));
                const std::string png = capture(chromium, page);
                check_png(png, o);
                write_atomically(work.path / fmt::format("frame{:05d}.png", i - first),
                                 [&](std::ostream& f) { f.write(png.data(), static_cast<std::streamsize>(png.size())); });
              }
            });
    std::vector<std::string> argv = {"ffmpeg", "-nostdin", "-hide_banner", "-loglevel", "error", "-y",
                                     "-framerate", fmt::format("{:.6g}", fps), "-i", (work.path / "frame%05d.png").string()};
    if (ext == ".mp4") argv.insert(argv.end(), {"-c:v", "libx264", "-pix_fmt", "yuv420p", "-crf", "18", "-movflags", "+faststart", "-f", "mp4"});
    else argv.insert(argv.end(), {"-filter_complex", "split[a][b];[a]palettegen=stats_mode=full[p];[b][p]paletteuse", "-f", "gif"});
    const fs::path encoded = work.path / ("video" + ext);
    argv.push_back(encoded.string());
    const fs::path log = work.path / "ffmpeg.log";
    int status = 0;
    try {
      status = run_program(argv, log);
    } catch (const EncoderError&) {
      throw EncoderError("snh render --video needs ffmpeg, and it could not be run: install the Debian package ffmpeg "
                         "(apt-get install ffmpeg)");
    }
    if (status != 0) throw EncoderError(fmt::format("ffmpeg failed (exit status {}): {}", status, last_line(log)));
    if (stop_requested()) throw BrowserInterrupted(stop_signal());
    std::ifstream video(encoded, std::ios::binary);
    write_atomically(out, [&](std::ostream& file) { file << video.rdbuf(); });
  }
  return {last - first + 1, fps};
}

}  // namespace snh
