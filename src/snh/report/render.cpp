#include "snh/report/render.hpp"

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string_view>
#include <vector>

#include <unistd.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/io/atomic_file.hpp"
#include "snh/io/base64.hpp"
#include "snh/report/browser.hpp"
#include "snh/report/report.hpp"
#include "snh/run/interrupt.hpp"

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

/// Opens `url` in a fresh headless browser (its profile, log and temporary files in `work`) with a
/// width by height view, waits until the page has drawn the frame (or reported why not) and returns the
/// PNG of the view. The browser is stopped when this returns or throws.
std::string screenshot(const std::string& browser, const std::string& url, const RenderOptions& o, const fs::path& work) {
  const std::vector<std::string> flags = {
      "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--disable-quic", "--no-first-run", "--no-startup-window",
      "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-extensions",
      "--mute-audio", "--user-data-dir=" + (work / "profile").string(),
      fmt::format("--window-size={},{}", o.width, o.height)};
  const fs::path temp = work / "tmp";
  std::error_code ec;
  if (!fs::create_directory(temp, ec))
    throw WriteError(fmt::format("cannot create {}: {}", temp.string(), ec ? ec.message() : "it exists"));
  HeadlessBrowser chromium(browser, flags, work / "browser.log", temp, o.timeout_seconds);
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
  const json shot = chromium.call("Page.captureScreenshot", {{"format", "png"}}, page);
  std::string png;
  if (!base64_decode(shot.value("data", std::string()), png))
    throw BrowserError("the browser's picture is not valid base64");
  return png;
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

}  // namespace

std::pair<int, int> png_size(const fs::path& png) {
  std::ifstream in(png, std::ios::binary);
  char head[24] = {};
  in.read(head, sizeof head);
  return png_header_size(std::string_view(head, static_cast<std::size_t>(in.gcount())));
}

void render_png(const fs::path& dir, const RenderOptions& o) {
  if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192)
    throw ReportError(fmt::format("the picture size must be from 16 to 8192 pixels each way, got {}x{}", o.width, o.height));
  if (o.out.empty()) throw ReportError("no output file given");
  const fs::path out = fs::absolute(o.out);
  check_output_path(out);
  if (!o.show.empty() && (o.show != "flesh" && o.show != "lbs" && o.show != "volume"))
    throw ReportError(fmt::format("--show {}: expected flesh, lbs or volume", o.show));
  if (!fs::exists(dir / "index.html") || !fs::exists(dir / "report" / "data.js")) (void)write_report(dir);
  // The frame and field are checked here, so that the page is only asked for what it has.
  const json data = read_report_data(dir);
  if (!data.contains("mesh") || data.at("mesh").is_null())
    throw ReportError(fmt::format("{}: the run has no 3D frames to render (no frames.pvd)", dir.string()));
  const json& mesh = data.at("mesh");
  const int frames = static_cast<int>(mesh.at("frames").size());
  const int frame = o.frame < 0 ? frames - 1 : o.frame;
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
  if (!o.show.empty() && (!data.contains("render") || data.at("render").is_null()))
    throw ReportError(fmt::format("--show {}: {} is not a flesh run (it has no render surface)", o.show, dir.string()));

  const std::string browser = find_browser(o.browser);
  if (browser.empty())
    throw BrowserError("snh render needs Chromium, and none was found on PATH: install the Debian package chromium "
                       "(apt-get install chromium), or set SNH_CHROMIUM to a Chromium or Chrome binary");
  if (::access(browser.c_str(), X_OK) != 0)
    throw ReportError(fmt::format("the browser {} cannot be run (from SNH_CHROMIUM or --browser)", browser));
  const std::string url = fmt::format("{}#render&frame={}&field={}{}{}", file_url(fs::absolute(dir / "index.html")), frame,
                                      field, o.wireframe ? "&wireframe=1" : "", o.show.empty() ? "" : "&show=" + o.show);
  // The browser is driven over its DevTools pipe, in real time: the picture is taken once the page says
  // it drew the frame, however long that takes (within the timeout). Every wait in here is interrupted by
  // a stop signal, after which the browser is killed and its directory removed before this returns, so a
  // second signal waits for that instead of ending the process at once.
  std::string png;
  {
    PromptStopScope prompt;
    if (stop_requested()) throw BrowserInterrupted(stop_signal());
    TempDir work;
    png = screenshot(browser, url, o, work.path);
  }
  if (stop_requested()) throw BrowserInterrupted(stop_signal());
  const auto [w, h] = png_header_size(png);
  if (w != o.width || h != o.height)
    throw BrowserError(w == 0 ? std::string("the browser's picture is not a PNG")
                              : fmt::format("the browser's picture is {}x{}, not {}x{}", w, h, o.width, o.height));
  write_atomically(out, [&](std::ostream& file) { file.write(png.data(), static_cast<std::streamsize>(png.size())); });
}

}  // namespace snh
