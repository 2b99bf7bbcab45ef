#include "snh/run/interrupt.hpp"

#include <atomic>
#include <csignal>

#include <pthread.h>
#include <unistd.h>

namespace snh {
namespace {

// Lock-free atomics: safe in a signal handler, and seen by every thread (the handler may run on any).
std::atomic<int> g_signal{0};         // the first stop signal (0: none)
std::atomic<int> g_prompt_scopes{0};  // PromptStopScopes alive
static_assert(std::atomic<int>::is_always_lock_free);

/// Ends the process now by `signal`'s default action (termination, seen by the parent as 128 + signal).
/// Only async-signal-safe calls: the handler runs wherever the signal found the process.
void end_by_default_action(int signal) {
  struct sigaction action {};
  action.sa_handler = SIG_DFL;
  sigemptyset(&action.sa_mask);
  sigaction(signal, &action, nullptr);
  sigset_t unblock;
  sigemptyset(&unblock);
  sigaddset(&unblock, signal);
  pthread_sigmask(SIG_UNBLOCK, &unblock, nullptr);  // it is blocked while its handler runs
  raise(signal);
  _exit(128 + signal);  // not reached: SIGINT's and SIGTERM's default action terminates
}

extern "C" void on_stop_signal(int signal) {
  int none = 0;
  if (!g_signal.compare_exchange_strong(none, signal) && g_prompt_scopes == 0) end_by_default_action(signal);
}

}  // namespace

void install_stop_handlers() {
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  sigaddset(&action.sa_mask, SIGINT);  // one handler at a time: a SIGTERM cannot interrupt SIGINT's
  sigaddset(&action.sa_mask, SIGTERM);
  action.sa_flags = 0;  // no SA_RESTART: a blocking call returns, the flag is seen soon after
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
}

bool stop_requested() { return g_signal != 0; }
int stop_signal() { return g_signal; }
void request_stop(int signal) { g_signal = signal; }

PromptStopScope::PromptStopScope() { ++g_prompt_scopes; }
PromptStopScope::~PromptStopScope() { --g_prompt_scopes; }

}  // namespace snh
