// Time behind an injectable interface: the pipeline, its latency counters, the simulated
// drivers (camera, IMU, status output) and the real ones (the V4L2 camera through its
// V4l2Io, libcamera, the IIO IMU) take a Clock, so tests drive time by hand. A real
// driver given no clock reads SystemMonotonicClock(); the kernel's own timestamps (V4L2
// buffers, libcamera's metadata, an IIO buffer's timestamp channel) are CLOCK_MONOTONIC,
// the time MonotonicClock reads, so the devices' timestamps and the pipeline's agree.
#pragma once

#include <chrono>
#include <cstdint>

namespace skyloc {

using Nanoseconds = std::chrono::nanoseconds;

class Clock {
 public:
  virtual ~Clock() = default;
  // Monotonic time since an arbitrary fixed origin; never goes backwards.
  virtual Nanoseconds Now() const = 0;
};

// CLOCK_MONOTONIC: the clock V4L2 buffer timestamps use, so camera and pipeline agree.
class MonotonicClock final : public Clock {
 public:
  Nanoseconds Now() const override;
};

// The process's MonotonicClock, for a driver constructed without a clock.
const Clock& SystemMonotonicClock();

// poll(2)'s timeout for a wait of at most `remaining`: whole milliseconds rounded up (a
// wait with time left never polls with 0, which would spin), at most a minute.
inline int PollTimeoutMs(Nanoseconds remaining) {
  if (remaining <= Nanoseconds(0))
    return 0;
  const auto ms = (remaining.count() + 999'999) / 1'000'000;
  return ms > 60'000 ? 60'000 : static_cast<int>(ms);
}

// A clock that moves only when told to (tests, replay at simulated pace).
class ManualClock final : public Clock {
 public:
  explicit ManualClock(Nanoseconds start = Nanoseconds{0}) : now_(start) {}
  Nanoseconds Now() const override { return now_; }
  void Advance(Nanoseconds by) { now_ += by < Nanoseconds{0} ? Nanoseconds{0} : by; }
  void Set(Nanoseconds to) {
    if (to > now_)
      now_ = to;
  }

 private:
  Nanoseconds now_;
};

}  // namespace skyloc
