// The decisions a streaming device's driver makes when its device misbehaves, kept apart
// from the system calls so a unit test can drive them with made-up times and errnos: the
// one backoff policy of the V4L2 camera and of every IMU (ImuDevice reopens any IMU with
// it, imu_device.h). In the manner of PX4's sensor drivers: a small state machine with a
// consecutive-failure counter.
//
//   kStreaming --device lost (ENODEV, EIO, ...) or stalled--> kBackingOff
//   kBackingOff --ReopenDue()--> driver closes & reopens --ok--> kStreaming (restart counted)
//                                                       --fail--> kBackingOff, backoff doubles
//   kBackingOff --max_failures consecutive failed reopens--> kFailed (Capture reports it)
//
// A stream is stalled when no frame arrived for `stall_timeout` while frames were
// expected (time since streaming started or since the last frame); the camera uses it.
// An IMU does not: its samples going stale is the attitude source's business, and only
// a device that is gone (ENODEV, the file vanished) is closed and reopened.
#pragma once

#include <cstdint>

#include "skyloc/platform/clock.h"

namespace skyloc::drivers {

struct StreamRecoveryConfig {
  Nanoseconds stall_timeout{std::chrono::seconds(2)};
  Nanoseconds backoff_initial{std::chrono::milliseconds(100)};
  Nanoseconds backoff_max{std::chrono::seconds(2)};
  std::uint32_t max_failures = 0;  // consecutive failed reopens before giving up; 0 = never
};

class StreamRecovery {
 public:
  enum class State : std::uint8_t { kStreaming, kBackingOff, kFailed };

  explicit StreamRecovery(const StreamRecoveryConfig& config = {}) : config_(config) {}

  // True for the errnos that mean the device went away or broke (close and reopen it),
  // as opposed to a caller bug (EINVAL) or a transient condition (EAGAIN, EINTR).
  static bool IsDeviceLoss(int saved_errno);

  // Streaming (re)started at `now`: forgets failures, arms the stall timer.
  void Started(Nanoseconds now);
  void FrameArrived(Nanoseconds now) { last_progress_ = now; }
  // When the stream counts as stalled if no frame arrives before.
  Nanoseconds stall_deadline() const { return last_progress_ + config_.stall_timeout; }
  bool IsStalled(Nanoseconds now) const {
    return state_ == State::kStreaming && now - last_progress_ >= config_.stall_timeout;
  }
  // The device failed or stalled: the driver has closed it; the first reopen is due
  // after the initial backoff.
  void DeviceLost(Nanoseconds now);
  bool ReopenDue(Nanoseconds now) const {
    return state_ == State::kBackingOff && now >= next_attempt_;
  }
  // A reopen attempt failed: back off twice as long (up to backoff_max), or give up.
  void ReopenFailed(Nanoseconds now);
  // A reopen succeeded and the stream runs again: counts a restart.
  void ReopenSucceeded(Nanoseconds now);

  State state() const { return state_; }
  std::uint32_t consecutive_failures() const { return failures_; }
  std::uint64_t restarts() const { return restarts_; }
  Nanoseconds next_attempt() const { return next_attempt_; }
  Nanoseconds backoff() const { return backoff_; }
  const StreamRecoveryConfig& config() const { return config_; }

 private:
  StreamRecoveryConfig config_;
  State state_ = State::kStreaming;
  std::uint32_t failures_ = 0;
  std::uint64_t restarts_ = 0;
  Nanoseconds last_progress_{0};
  Nanoseconds next_attempt_{0};
  Nanoseconds backoff_{0};
};

}  // namespace skyloc::drivers
