#pragma once
// Headless Chromium driven over the DevTools protocol on a pipe (--remote-debugging-pipe: the browser
// reads commands on its fd 3 and writes replies and events on its fd 4, each a JSON text ended by a NUL
// byte). Every wait is in real time, against one deadline, and ends at once when a stop is requested
// (SIGINT, SIGTERM: snh::install_stop_handlers). The browser runs in its own process group, killed whole
// when the session ends however it ends.
#include <chrono>
#include <deque>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <sys/types.h>

#include <nlohmann/json.hpp>

#include "snh/report/report.hpp"

namespace snh {

/// The browser failed at run time: it could not be started, it exited, crashed or did not answer in
/// time, or it refused a command. One line, with the last line of the browser's log where that helps.
class BrowserError : public ReportError {
 public:
  using ReportError::ReportError;
};

/// A stop was requested (SIGINT or SIGTERM) while waiting for the browser: it was stopped.
class BrowserInterrupted : public ReportError {
 public:
  explicit BrowserInterrupted(int signal)
      : ReportError("interrupted by signal " + std::to_string(signal) + ": the browser was stopped, nothing was written"),
        signal(signal) {}
  int signal;
};

/// One headless browser and its DevTools pipe.
class HeadlessBrowser {
 public:
  /// Starts `binary` with --headless, --remote-debugging-pipe and `flags`, its output (stdout and stderr)
  /// going to `log` and its own temporary files (Chromium's org.chromium.* directories, which a killed
  /// browser leaves behind) into `temp_dir` (its TMPDIR); every wait of this session ends
  /// `timeout_seconds` from now. Throws BrowserError.
  HeadlessBrowser(const std::string& binary, const std::vector<std::string>& flags, const std::filesystem::path& log,
                  const std::filesystem::path& temp_dir, double timeout_seconds);
  /// Kills the browser's process group and waits for the browser.
  ~HeadlessBrowser();
  HeadlessBrowser(const HeadlessBrowser&) = delete;
  HeadlessBrowser& operator=(const HeadlessBrowser&) = delete;

  /// Sends the command `method` (to the target attached as `session`, or to the browser when empty) and
  /// returns its result; the events that arrive meanwhile are kept for wait_for_event. Throws BrowserError
  /// (naming the command and the browser's reason when it refuses) or BrowserInterrupted.
  nlohmann::json call(const std::string& method, const nlohmann::json& params = nlohmann::json::object(),
                      const std::string& session = "");
  /// Waits for the event `method` of `session` whose parameters `match` (a kept one first) and returns
  /// those parameters; other events that arrive meanwhile are dropped. Throws like call.
  nlohmann::json wait_for_event(const std::string& method, const std::string& session,
                                const std::function<bool(const nlohmann::json&)>& match);

 private:
  /// The next message from the browser, waiting for it while `doing` (named in errors).
  nlohmann::json receive(const std::string& doing);
  /// The pipe closed: the browser is ending. Reaps it and throws BrowserError with its status.
  [[noreturn]] void fail_exited(const std::string& doing);
  /// The last telling line of the browser's log.
  [[nodiscard]] std::string what_it_said() const;

  std::string binary_;
  std::filesystem::path log_;
  double timeout_seconds_;
  std::chrono::steady_clock::time_point deadline_;
  pid_t pid_ = -1;   ///< the browser, leader of its process group (-1 once reaped)
  int status_ = 0;   ///< its wait status once reaped
  int pipe_ = -1;    ///< our end of the socket pair
  int next_id_ = 0;
  std::string pending_;                 ///< bytes read past the last complete message
  std::size_t searched_ = 0;            ///< how much of pending_ holds no NUL
  std::deque<nlohmann::json> events_;  ///< events read while waiting for a reply
};

}  // namespace snh
