// ParallelErrors: an exception thrown in an OpenMP parallel loop (a std::bad_alloc in an element loop)
// comes out after the loop instead of ending the process, and it is the one of the lowest iteration that
// threw, whatever the thread count.
#include <gtest/gtest.h>

#include <omp.h>

#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include "snh/math/parallel.hpp"

namespace snh {
namespace {

/// Runs n iterations on `threads` threads; iteration i throws when throws_at(i) is not empty.
template <class Throw>
void loop(int n, int threads, Throw&& throw_at, std::vector<int>& done) {
  ParallelErrors errors;
  done.assign(static_cast<std::size_t>(n), 0);
#pragma omp parallel for schedule(static) num_threads(threads)
  for (int i = 0; i < n; ++i) {
    errors.run(i, [&] {
      throw_at(i);
      done[static_cast<std::size_t>(i)] = 1;
    });
  }
  errors.rethrow();
}

TEST(ParallelErrors, TheLowestThrowingIterationsExceptionComesOutAfterTheLoop) {
  for (const int threads : {1, 2, 4, 7}) {
    std::vector<int> done;
    try {
      loop(1000, threads, [](int i) {
        if (i == 900) throw std::runtime_error("iteration 900");
        if (i == 301) throw std::invalid_argument("iteration 301");
      }, done);
      ADD_FAILURE() << "no exception with " << threads << " threads";
    } catch (const std::invalid_argument& e) {
      EXPECT_EQ(std::string(e.what()), "iteration 301") << threads << " threads";
    }
    for (int i = 0; i < 301; ++i) EXPECT_EQ(done[static_cast<std::size_t>(i)], 1) << "iteration " << i << " ran";
  }
}

TEST(ParallelErrors, ABadAllocStaysABadAlloc) {
  std::vector<int> done;
  EXPECT_THROW(loop(64, 2, [](int i) { if (i == 40) throw std::bad_alloc(); }, done), std::bad_alloc);
  EXPECT_NO_THROW(loop(64, 2, [](int) {}, done));
  for (int d : done) EXPECT_EQ(d, 1);
}

}  // namespace
}  // namespace snh
