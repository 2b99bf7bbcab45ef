#include "snh/report/browser.hpp"

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <string_view>
#include <thread>

#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include "snh/run/interrupt.hpp"

extern char** environ;

namespace snh {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;
using Clock = std::chrono::steady_clock;

/// `fd` moved to a descriptor numbered 10 or more, close-on-exec: the child's fds 3 and 4 are made from
/// it with dup2, which would leave a descriptor already numbered 3 or 4 close-on-exec.
int moved_high(int fd) {
  const int moved = ::fcntl(fd, F_DUPFD_CLOEXEC, 10);
  ::close(fd);
  return moved;
}

/// "exit status N" or "killed by signal N" for a wait status.
std::string describe(int status) {
  return WIFSIGNALED(status) ? fmt::format("killed by signal {}", WTERMSIG(status))
                             : fmt::format("exit status {}", WEXITSTATUS(status));
}

/// The last non-empty line of the log that is not one of Chromium's routine complaints (D-Bus, its
/// software WebGL fallback) or a complaint of the shell script that starts it (Debian's /usr/bin/chromium:
/// "NAME: LINE: ...").
std::string last_log_line(const fs::path& log, const std::string& browser) {
  std::ifstream in(log, std::ios::binary);
  std::string last;
  for (std::string line; std::getline(in, line);)
    if (!line.empty() && line.find("dbus") == std::string::npos && line.find("GL Driver Message") == std::string::npos &&
        line.find("software WebGL") == std::string::npos && line.rfind(browser + ":", 0) != 0)
      last = line;
  return last.empty() ? "(no output)" : last;
}

}  // namespace

HeadlessBrowser::HeadlessBrowser(const std::string& binary, const std::vector<std::string>& flags, const fs::path& log,
                                 const fs::path& temp_dir, double timeout_seconds)
    : binary_(binary),
      log_(log),
      timeout_seconds_(timeout_seconds),
      deadline_(Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_seconds))) {
  int ends[2];
  if (::socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, ends) != 0)
    throw BrowserError(fmt::format("cannot make a pipe to the browser: {}", std::strerror(errno)));
  pipe_ = moved_high(ends[0]);
  const int theirs = moved_high(ends[1]);
  if (pipe_ < 0 || theirs < 0) {
    const std::string reason = std::strerror(errno);
    if (pipe_ >= 0) ::close(pipe_);
    if (theirs >= 0) ::close(theirs);
    throw BrowserError("cannot make a pipe to the browser: " + reason);
  }
  std::vector<std::string> args = {binary, "--headless", "--remote-debugging-pipe"};
  args.insert(args.end(), flags.begin(), flags.end());
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  std::vector<std::string> variables = {"TMPDIR=" + temp_dir.string()};
  for (char** v = environ; *v; ++v)
    if (std::string_view(*v).rfind("TMPDIR=", 0) != 0) variables.emplace_back(*v);
  std::vector<char*> envp;
  for (std::string& v : variables) envp.push_back(v.data());
  envp.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  posix_spawn_file_actions_adddup2(&actions, theirs, 3);  // it reads commands here
  posix_spawn_file_actions_adddup2(&actions, theirs, 4);  // and writes replies and events here
  posix_spawnattr_t attr;
  posix_spawnattr_init(&attr);
  posix_spawnattr_setpgroup(&attr, 0);  // its own process group: Ctrl-C at a terminal reaches only us, and
                                        // killing the group stops every process it started
  sigset_t none;
  sigemptyset(&none);
  posix_spawnattr_setsigmask(&attr, &none);
  posix_spawnattr_setflags(&attr, POSIX_SPAWN_SETPGROUP | POSIX_SPAWN_SETSIGMASK);
  const int err = posix_spawn(&pid_, binary.c_str(), &actions, &attr, argv.data(), envp.data());
  posix_spawn_file_actions_destroy(&actions);
  posix_spawnattr_destroy(&attr);
  ::close(theirs);
  if (err != 0) {
    ::close(pipe_);
    throw BrowserError(fmt::format("cannot start the browser {}: {}", binary, std::strerror(err)));
  }
}

HeadlessBrowser::~HeadlessBrowser() {
  ::close(pipe_);  // a browser on a closed pipe quits; the kill does not wait for that
  if (pid_ > 0) {
    ::kill(-pid_, SIGKILL);
    while (::waitpid(pid_, &status_, 0) < 0 && errno == EINTR) {
    }
  }
}

std::string HeadlessBrowser::what_it_said() const { return last_log_line(log_, binary_); }

void HeadlessBrowser::fail_exited(const std::string& doing) {
  // The pipe closed: the browser is ending. Give it a moment to exit by itself, for its own status.
  const auto until = std::min(Clock::now() + std::chrono::seconds(2), deadline_);
  pid_t reaped = 0;
  while ((reaped = ::waitpid(pid_, &status_, WNOHANG)) == 0 && Clock::now() < until)
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  ::kill(-pid_, SIGKILL);  // what it started
  if (reaped == 0)
    while (::waitpid(pid_, &status_, 0) < 0 && errno == EINTR) {
    }
  pid_ = -1;
  throw BrowserError(fmt::format("the browser {} ended ({}) during {}: {}", binary_, describe(status_), doing, what_it_said()));
}

json HeadlessBrowser::receive(const std::string& doing) {
  for (;;) {
    if (const std::size_t end = pending_.find('\0', searched_); end != std::string::npos) {
      json message = json::parse(pending_.begin(), pending_.begin() + static_cast<std::ptrdiff_t>(end), nullptr, false);
      pending_.erase(0, end + 1);
      searched_ = 0;
      if (message.is_discarded() || !message.is_object())
        throw BrowserError(fmt::format("the browser {} sent something that is not a DevTools message during {}", binary_, doing));
      if (message.value("method", std::string()) == "Inspector.targetCrashed")
        throw BrowserError(fmt::format("the page crashed in the browser {} during {}: {}", binary_, doing, what_it_said()));
      return message;
    }
    searched_ = pending_.size();  // a long message (the picture) comes in many reads: look only at what is new
    if (stop_requested()) throw BrowserInterrupted(stop_signal());
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline_ - Clock::now()).count();
    if (left <= 0)
      throw BrowserError(fmt::format("the browser {} did not finish within {:g} s (waiting for {})", binary_, timeout_seconds_, doing));
    // A stop signal interrupts poll (no SA_RESTART); the 100 ms bound covers one that came just before it.
    pollfd p{pipe_, POLLIN, 0};
    const int ready = ::poll(&p, 1, static_cast<int>(std::min<long long>(left, 100)));
    if (ready < 0 && errno != EINTR) throw BrowserError(fmt::format("waiting for the browser: {}", std::strerror(errno)));
    if (ready <= 0) continue;
    char chunk[1 << 16];
    const ssize_t n = ::read(pipe_, chunk, sizeof chunk);
    if (n == 0 || (n < 0 && errno == ECONNRESET)) fail_exited(doing);
    if (n < 0 && errno != EINTR && errno != EAGAIN)
      throw BrowserError(fmt::format("reading from the browser: {}", std::strerror(errno)));
    if (n > 0) pending_.append(chunk, static_cast<std::size_t>(n));
  }
}

json HeadlessBrowser::call(const std::string& method, const json& params, const std::string& session) {
  const int id = ++next_id_;
  json command = {{"id", id}, {"method", method}, {"params", params}};
  if (!session.empty()) command["sessionId"] = session;
  std::string text = command.dump();
  text.push_back('\0');
  for (std::size_t sent = 0; sent < text.size();) {
    const ssize_t n = ::send(pipe_, text.data() + sent, text.size() - sent, MSG_NOSIGNAL);
    if (n >= 0) {
      sent += static_cast<std::size_t>(n);
    } else if (errno == EPIPE || errno == ECONNRESET) {
      fail_exited(method);
    } else if (errno == EINTR) {
      if (stop_requested()) throw BrowserInterrupted(stop_signal());
    } else {
      throw BrowserError(fmt::format("writing to the browser: {}", std::strerror(errno)));
    }
  }
  for (;;) {
    json message = receive(method);
    if (!message.contains("id")) {
      events_.push_back(std::move(message));
      continue;
    }
    if (message["id"] != id) continue;  // a reply nobody waits for
    if (message.contains("error"))
      throw BrowserError(fmt::format("the browser {} refused {}: {}", binary_, method, message["error"].value("message", message["error"].dump())));
    return message.value("result", json::object());
  }
}

json HeadlessBrowser::wait_for_event(const std::string& method, const std::string& session,
                                     const std::function<bool(const json&)>& match) {
  auto wanted = [&](const json& m) {
    return m.value("method", std::string()) == method && m.value("sessionId", std::string()) == session &&
           match(m.value("params", json::object()));
  };
  for (auto it = events_.begin(); it != events_.end(); ++it)
    if (wanted(*it)) {
      json params = it->value("params", json::object());
      events_.erase(it);
      return params;
    }
  for (;;) {
    json message = receive(method);
    if (wanted(message)) return message.value("params", json::object());
  }
}

}  // namespace snh
