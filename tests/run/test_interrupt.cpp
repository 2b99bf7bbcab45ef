// Stop signals: the first SIGINT or SIGTERM only asks for a stop; a second one ends the process at once,
// by that signal, even while it is busy in code that never looks at the flag (a long CHOLMOD or OpenBLAS
// call); inside a PromptStopScope the second one is only recorded. Each case runs in a child process
// (a death test) whose stuck loop gives up after a few seconds, so a missing exit fails instead of hanging.
#include <gtest/gtest.h>

#include <chrono>
#include <csignal>
#include <thread>

#include <unistd.h>

#include "snh/run/interrupt.hpp"

namespace snh {
namespace {

/// Busy for up to `seconds` without looking at the stop flag, as a library call would be.
void stay_busy(double seconds) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(seconds);
  volatile double x = 0;
  while (std::chrono::steady_clock::now() < end) x = x + 1;
}

/// Sends `first` then `second` to this process from another thread, 50 ms apart, while this thread is
/// busy; exits 0 if the process is still alive 5 s later, 3 if the first signal was not recorded.
void signal_twice_while_busy(int first, int second) {
  install_stop_handlers();
  request_stop(0);
  std::thread sender([=] {
    ::kill(::getpid(), first);
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    if (stop_signal() != first) _exit(3);
    ::kill(::getpid(), second);
  });
  sender.detach();
  stay_busy(5.0);
  _exit(0);
}

class Interrupt : public ::testing::Test {
 protected:
  void SetUp() override { GTEST_FLAG_SET(death_test_style, "threadsafe"); }
};

TEST_F(Interrupt, TheFirstSignalOnlyAsksForAStop) {
  EXPECT_EXIT(
      {
        install_stop_handlers();
        request_stop(0);
        ::raise(SIGINT);
        _exit(stop_requested() && stop_signal() == SIGINT ? 7 : 1);
      },
      ::testing::ExitedWithCode(7), "");
}

TEST_F(Interrupt, ASecondCtrlCEndsABusyProcessAtOnce) {
  EXPECT_EXIT(signal_twice_while_busy(SIGINT, SIGINT), ::testing::KilledBySignal(SIGINT), "");
}

TEST_F(Interrupt, SigtermAfterCtrlCEndsItBySigterm) {
  EXPECT_EXIT(signal_twice_while_busy(SIGINT, SIGTERM), ::testing::KilledBySignal(SIGTERM), "");
}

TEST_F(Interrupt, InsideAPromptStopScopeASecondSignalIsOnlyRecorded) {
  EXPECT_EXIT(
      {
        install_stop_handlers();
        request_stop(0);
        {
          PromptStopScope prompt;
          ::raise(SIGINT);
          ::raise(SIGINT);
          ::raise(SIGTERM);
          if (stop_signal() != SIGINT) _exit(1);
        }
        ::raise(SIGTERM);  // outside the scope again: a second signal ends it
        _exit(0);
      },
      ::testing::KilledBySignal(SIGTERM), "");
}

}  // namespace
}  // namespace snh
