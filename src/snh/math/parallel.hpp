#pragma once
// Exceptions and OpenMP (docs/design.md): an exception that leaves an OpenMP parallel region ends the
// process (std::terminate), so a std::bad_alloc in an element loop aborted a run instead of reaching its
// out-of-memory line. Every parallel loop runs its body through ParallelErrors::run and calls rethrow()
// after the region: the exception of the lowest iteration that threw is rethrown there, the same for any
// thread count, and the iterations after it are skipped.
#include <atomic>
#include <cstdint>
#include <cstdlib>
#include <exception>
#include <limits>
#include <mutex>
#include <new>

namespace snh {

namespace detail {
/// Tests only: SNH_TEST_BAD_ALLOC=N makes the Nth iteration (counted from 1, over all guarded parallel
/// loops of the process) throw std::bad_alloc, to test the path a real one takes. Unset: never.
inline const std::int64_t test_bad_alloc_at = [] {
  const char* env = std::getenv("SNH_TEST_BAD_ALLOC");
  return env ? std::strtoll(env, nullptr, 10) : std::int64_t{0};
}();
inline std::atomic<std::int64_t> test_iterations{0};
}  // namespace detail

class ParallelErrors {
 public:
  /// Runs body() for iteration i; an exception it throws is kept (the one of the lowest i), never let out.
  template <class Body>
  void run(std::int64_t i, Body&& body) noexcept {
    if (i > first_.load(std::memory_order_relaxed)) return;  // a lower iteration failed: skipped
    try {
      if (detail::test_bad_alloc_at > 0) [[unlikely]]
        if (detail::test_iterations.fetch_add(1) + 1 == detail::test_bad_alloc_at) throw std::bad_alloc();
      body();
    } catch (...) {
      const std::lock_guard<std::mutex> lock(mutex_);
      if (i < first_.load(std::memory_order_relaxed)) {
        first_.store(i, std::memory_order_relaxed);
        error_ = std::current_exception();
      }
    }
  }
  /// After the parallel region: throws the kept exception, if any.
  void rethrow() const {
    if (error_) std::rethrow_exception(error_);
  }

 private:
  std::atomic<std::int64_t> first_{std::numeric_limits<std::int64_t>::max()};
  std::mutex mutex_;
  std::exception_ptr error_;
};

}  // namespace snh
