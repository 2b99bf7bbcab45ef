#pragma once
// Stopping a long run cleanly (DESIGN.md sim/): SIGINT (Ctrl-C) and SIGTERM set a flag; the runners
// check it between Newton iterations, abandon the step in progress, keep every completed frame and
// write their stats, and the programs exit with 128 + the signal number.
namespace snh {

/// Installs the SIGINT and SIGTERM handlers (idempotent).
void install_stop_handlers();
/// True once a stop was requested; the signal that asked (0 if none).
[[nodiscard]] bool stop_requested();
[[nodiscard]] int stop_signal();
/// Requests a stop as if `signal` had arrived (tests), or clears the request with 0.
void request_stop(int signal);

}  // namespace snh
