#include "skyloc/platform/clock.h"

#include <time.h>

namespace skyloc {

Nanoseconds MonotonicClock::Now() const {
  timespec ts{};
  // CLOCK_MONOTONIC cannot fail with a valid clock id and pointer.
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return Nanoseconds{static_cast<std::int64_t>(ts.tv_sec) * 1'000'000'000 + ts.tv_nsec};
}

const Clock& SystemMonotonicClock() {
  static const MonotonicClock clock;
  return clock;
}

}  // namespace skyloc
