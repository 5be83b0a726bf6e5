#include "skyloc/drivers/stream_recovery.h"

#include <cerrno>

namespace skyloc::drivers {

bool StreamRecovery::IsDeviceLoss(int saved_errno) {
  switch (saved_errno) {
    case ENODEV:     // unplugged, driver unbound, module removed
    case ENXIO:      // same, from some drivers
    case EIO:        // the device or its bus failed
    case EPIPE:      // the media pipeline broke (vimc: links no longer valid)
    case ESHUTDOWN:  // USB endpoint shut down
    case EBADF:      // our descriptor is no longer usable
      return true;
    default:
      return false;
  }
}

void StreamRecovery::Started(Nanoseconds now) {
  state_ = State::kStreaming;
  failures_ = 0;
  backoff_ = Nanoseconds(0);
  last_progress_ = now;
}

void StreamRecovery::DeviceLost(Nanoseconds now) {
  if (state_ == State::kFailed)
    return;
  state_ = State::kBackingOff;
  backoff_ = config_.backoff_initial;
  next_attempt_ = now + backoff_;
}

void StreamRecovery::ReopenFailed(Nanoseconds now) {
  if (state_ != State::kBackingOff)
    return;
  ++failures_;
  if (config_.max_failures != 0 && failures_ >= config_.max_failures) {
    state_ = State::kFailed;
    return;
  }
  backoff_ = backoff_ * 2 > config_.backoff_max ? config_.backoff_max : backoff_ * 2;
  next_attempt_ = now + backoff_;
}

void StreamRecovery::ReopenSucceeded(Nanoseconds now) {
  if (state_ != State::kBackingOff)
    return;
  ++restarts_;
  Started(now);
}

}  // namespace skyloc::drivers
