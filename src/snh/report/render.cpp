#include "snh/report/render.hpp"

#include <cctype>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>
#include <vector>

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "snh/report/report.hpp"
#include "snh/sim/interrupt.hpp"

extern char** environ;

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

std::string read_text(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

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

/// A temporary directory, removed when this goes out of scope.
struct TempDir {
  fs::path path;
  TempDir() {
    std::string templ = (fs::temp_directory_path() / "snh-render-XXXXXX").string();
    if (!::mkdtemp(templ.data())) throw ReportError("cannot create a temporary directory for the browser");
    path = templ;
  }
  ~TempDir() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

/// Runs the browser with `args` (its output to `log`); returns its exit status. Kills it (and what it
/// started) after `timeout` seconds, or when a stop is requested (SIGINT, SIGTERM: RenderInterrupted).
int run_browser(const std::string& browser, const std::vector<std::string>& args, const fs::path& log, double timeout) {
  std::vector<char*> argv;
  std::vector<std::string> all = {browser};
  all.insert(all.end(), args.begin(), args.end());
  for (std::string& a : all) argv.push_back(a.data());
  argv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setpgroup(&attr, 0);  // its own process group, so a timeout can stop all of it
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, browser.c_str(), &actions, &attr, argv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  if (err != 0) throw ReportError(fmt::format("cannot start the browser {}: {}", browser, std::strerror(err)));
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  for (;;) {
    const pid_t r = ::waitpid(pid, &status, WNOHANG);
    if (r == pid) break;
    if (r < 0 && errno != EINTR) throw ReportError(fmt::format("waiting for the browser: {}", std::strerror(errno)));
    if (stop_requested()) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw RenderInterrupted(stop_signal());
    }
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() > timeout) {
      ::kill(-pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      throw ReportError(fmt::format("the browser {} did not finish within {:g} s", browser, timeout));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ::kill(-pid, SIGKILL);  // helpers it may have left behind
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

/// The last non-empty line of a log that is not one of Chromium's routine complaints (D-Bus) or a
/// complaint of the shell script that starts it (Debian's /usr/bin/chromium: "NAME: LINE: ...").
std::string last_log_line(const fs::path& log, const std::string& browser) {
  std::istringstream in(read_text(log));
  std::string last;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line.find("dbus") == std::string::npos && line.rfind(browser + ":", 0) != 0) last = line;
  return last.empty() ? "(no output)" : last;
}

}  // namespace

std::pair<int, int> png_size(const fs::path& png) {
  const std::string head = read_text(png).substr(0, 24);
  if (head.size() < 24 || head.compare(0, 8, "\x89PNG\r\n\x1a\n") != 0 || head.compare(12, 4, "IHDR") != 0) return {0, 0};
  auto be32 = [&](int at) {
    return (static_cast<unsigned char>(head[at]) << 24) | (static_cast<unsigned char>(head[at + 1]) << 16) |
           (static_cast<unsigned char>(head[at + 2]) << 8) | static_cast<unsigned char>(head[at + 3]);
  };
  return {be32(16), be32(20)};
}

void render_png(const fs::path& dir, const RenderOptions& o) {
  if (o.width < 16 || o.height < 16 || o.width > 8192 || o.height > 8192)
    throw ReportError(fmt::format("the picture size must be from 16 to 8192 pixels each way, got {}x{}", o.width, o.height));
  if (o.out.empty()) throw ReportError("no output file given");
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

  const std::string browser = find_browser(o.browser);
  if (browser.empty() || ::access(browser.c_str(), X_OK) != 0)
    throw ReportError(browser.empty() ? "snh render needs Chromium, and none was found on PATH: install the Debian package "
                                        "chromium (apt-get install chromium), or set SNH_CHROMIUM to a Chromium or Chrome binary"
                                      : fmt::format("the browser {} cannot be run (from SNH_CHROMIUM or --browser)", browser));
  const fs::path out = fs::absolute(o.out);
  if (out.has_parent_path() && !fs::is_directory(out.parent_path()))
    throw ReportError(fmt::format("{}: the directory does not exist", out.parent_path().string()));

  TempDir tmp;
  if (!o.show.empty() && (o.show != "flesh" && o.show != "lbs" && o.show != "volume"))
    throw ReportError(fmt::format("--show {}: expected flesh, lbs or volume", o.show));
  if (!o.show.empty() && (!data.contains("render") || data.at("render").is_null()))
    throw ReportError(fmt::format("--show {}: {} is not a flesh run (it has no render surface)", o.show, dir.string()));
  const std::string url = fmt::format("{}#render&frame={}&field={}{}{}", file_url(fs::absolute(dir / "index.html")), frame,
                                      field, o.wireframe ? "&wireframe=1" : "", o.show.empty() ? "" : "&show=" + o.show);
  const std::vector<std::string> common = {
      "--headless", "--no-sandbox", "--disable-gpu", "--hide-scrollbars", "--disable-quic", "--no-first-run",
      "--disable-background-networking", "--disable-component-update", "--disable-sync", "--disable-extensions",
      "--mute-audio", "--user-data-dir=" + (tmp.path / "profile").string(),
      fmt::format("--window-size={},{}", o.width, o.height), "--virtual-time-budget=20000"};
  // One browser run loads the page, lets it draw the frame, dumps the DOM (whose title says whether the
  // page drew it) and then takes the picture, to a temporary name beside the output. The page's work runs
  // in virtual time while the GPU process draws in real time, so on a busy machine the budget can run out
  // before the page is done (its title is then still the report's): that run is repeated, up to 4 times.
  const fs::path partial = out.string() + fmt::format(".partial.{}.png", ::getpid());
  const fs::path log = tmp.path / "browser.log";
  std::vector<std::string> args = common;
  args.push_back("--dump-dom");
  args.push_back("--screenshot=" + partial.string());
  args.push_back(url);
  auto discard = [&] {
    std::error_code ec;
    fs::remove(partial, ec);
  };
  int status = 0;
  for (int attempt = 1;; ++attempt) {
    try {
      status = run_browser(browser, args, log, o.timeout_seconds);
    } catch (...) {
      discard();
      throw;
    }
    const std::string dom = read_text(log);
    if (dom.find("<title>snh-render-ready</title>") != std::string::npos) break;
    discard();
    const std::size_t at = dom.find("<title>snh-render-error: ");
    if (at != std::string::npos)
      throw ReportError("the report page: " + dom.substr(at + 25, dom.find("</title>", at) - at - 25));
    if (attempt == 4)
      throw ReportError(fmt::format("the browser did not draw the frame in {} tries (exit status {}): {}", attempt, status,
                                    last_log_line(log, browser)));
  }
  const auto [w, h] = fs::exists(partial) ? png_size(partial) : std::pair<int, int>{0, 0};
  if (w != o.width || h != o.height) {
    std::error_code ec;
    fs::remove(partial, ec);
    throw ReportError(w == 0 ? fmt::format("the browser wrote no picture (exit status {}): {}", status, last_log_line(log, browser))
                             : fmt::format("the browser's picture is {}x{}, not {}x{}", w, h, o.width, o.height));
  }
  std::error_code ec;
  fs::rename(partial, out, ec);
  if (ec) {
    fs::remove(partial, ec);
    throw ReportError(fmt::format("{}: cannot be written: {}", out.string(), ec.message()));
  }
}

}  // namespace snh
