#pragma once
// Stopping a long run cleanly (docs/design.md): the first SIGINT (Ctrl-C) or SIGTERM sets a flag; the
// runners check it between Newton iterations, abandon the step in progress, keep every completed frame
// and write their stats, and the programs exit with 128 + the signal number. A second SIGINT or SIGTERM
// ends the process at once, as the signal's default action would (exit status 128 + that signal), even
// inside a long library call (a CHOLMOD factorization, an OpenBLAS kernel) that never looks at the flag.
namespace snh {

/// Installs the SIGINT and SIGTERM handlers (idempotent).
void install_stop_handlers();
/// True once a stop was requested; the signal that asked (0 if none).
[[nodiscard]] bool stop_requested();
[[nodiscard]] int stop_signal();
/// Requests a stop as if `signal` had arrived (tests), or clears the request with 0.
void request_stop(int signal);

/// While one lives, a second SIGINT or SIGTERM is only recorded, like the first: for code that waits only
/// in calls a signal interrupts, checks stop_requested() after each, and then cleans up in bounded time
/// (snh render stops its browser and removes its temporary profile before it exits). Nests.
class PromptStopScope {
 public:
  PromptStopScope();
  ~PromptStopScope();
  PromptStopScope(const PromptStopScope&) = delete;
  PromptStopScope& operator=(const PromptStopScope&) = delete;
};

}  // namespace snh
