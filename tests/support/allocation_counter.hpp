#pragma once
// Counts heap allocations made by the current thread: every test binary links a replacement of the
// global operator new/delete and (glibc, no ASan) an interposer of malloc/calloc/realloc, so that
// Eigen's allocations inside libphri are seen too (allocation_counter.cpp). Use with
// EIGEN_RUNTIME_NO_MALLOC as well, which asserts on Eigen allocations in the test's own code:
//
//   phri::test::AllocationCounter count;          // starts counting at zero
//   run_the_cycle();
//   EXPECT_EQ(count.allocations(), 0u);
//
// NoMallocScope additionally makes Eigen assert on any of its own allocations in the scope
// (compile the test with EIGEN_RUNTIME_NO_MALLOC defined, as tests/CMakeLists.txt does).
#include <cstddef>

#ifdef EIGEN_RUNTIME_NO_MALLOC
#include <Eigen/Core>
#endif

namespace phri::test {

std::size_t thread_allocation_count();
/// True when malloc/calloc/realloc are counted too (not under AddressSanitizer).
bool counts_malloc();

class AllocationCounter {
public:
  AllocationCounter() : start_(thread_allocation_count()) {}
  std::size_t allocations() const { return thread_allocation_count() - start_; }

private:
  std::size_t start_;
};

class NoMallocScope {
public:
#ifdef EIGEN_RUNTIME_NO_MALLOC
  NoMallocScope() { Eigen::internal::set_is_malloc_allowed(false); }
  ~NoMallocScope() { Eigen::internal::set_is_malloc_allowed(true); }
#endif
  NoMallocScope(const NoMallocScope&) = delete;
  NoMallocScope& operator=(const NoMallocScope&) = delete;
};

}  // namespace phri::test
