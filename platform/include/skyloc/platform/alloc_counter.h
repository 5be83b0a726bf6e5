// Counts heap allocations, to prove that the per-frame path allocates nothing.
//
// Linking the skyloc::alloc_counter target replaces the global operator new/delete (all
// forms) and, outside sanitizer builds, malloc/calloc/realloc, so C libraries that
// allocate behind our back are counted too. Counting is global (all threads), because a
// camera thread allocating on our behalf is as bad as the pipeline thread doing it.
//
//   skyloc::AllocationScope scope;      // arms the counter
//   RunLoop();
//   EXPECT_EQ(scope.allocations(), 0u);
#pragma once

#include <cstdint>

namespace skyloc {

struct AllocationTotals {
  std::uint64_t allocations = 0;  // calls that returned (or tried to return) memory
  std::uint64_t bytes = 0;        // bytes requested by those calls
};

// Totals since the process started, counted whether or not a scope is armed.
AllocationTotals AllocationTotalsNow();
// True when this binary's allocations are actually being counted (the counter library is
// linked); tests assert it so that a build mistake cannot make them pass vacuously.
bool AllocationCounterActive();

class AllocationScope {
 public:
  AllocationScope() : start_(AllocationTotalsNow()) {}
  std::uint64_t allocations() const {
    return AllocationTotalsNow().allocations - start_.allocations;
  }
  std::uint64_t bytes() const { return AllocationTotalsNow().bytes - start_.bytes; }

 private:
  AllocationTotals start_;
};

}  // namespace skyloc
