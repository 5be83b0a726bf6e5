// Time behind an injectable interface: the pipeline, its latency counters and the simulated
// drivers (camera, IMU, status output) take a Clock, so tests drive time by hand. The real
// devices (V4L2, libcamera, the IIO IMU) stamp their samples with CLOCK_MONOTONIC themselves,
// the time MonotonicClock reads, so their timestamps and the pipeline's agree.
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
