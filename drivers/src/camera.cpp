#include "skyloc/drivers/camera.h"

namespace skyloc::drivers {

const char* CameraStateName(Camera::State state) {
  switch (state) {
    case Camera::State::kClosed:
      return "closed";
    case Camera::State::kOpen:
      return "open";
    case Camera::State::kStreaming:
      return "streaming";
  }
  return "unknown";
}

Status Camera::Open() {
  if (state_ != State::kClosed) {
    return Status::Error(StatusCode::kFailedPrecondition, "camera %s: Open() while %s", info_.name,
                         CameraStateName(state_));
  }
  SKYLOC_TRY(DoOpen());
  state_ = State::kOpen;
  return Status::Ok();
}

Status Camera::Start() {
  if (state_ != State::kOpen) {
    return Status::Error(StatusCode::kFailedPrecondition, "camera %s: Start() while %s", info_.name,
                         CameraStateName(state_));
  }
  SKYLOC_TRY(DoStart());
  state_ = State::kStreaming;
  return Status::Ok();
}

Result<Frame> Camera::Capture(Nanoseconds timeout) {
  if (state_ != State::kStreaming) {
    ++counters_.errors;
    return Status::Error(StatusCode::kFailedPrecondition, "camera %s: Capture() while %s",
                         info_.name, CameraStateName(state_));
  }
  Result<Frame> frame = DoCapture(timeout);
  if (frame.ok())
    ++counters_.frames;
  else if (frame.status().code() != StatusCode::kDeadlineExceeded &&
           frame.status().code() != StatusCode::kOutOfRange)
    ++counters_.errors;
  return frame;
}

void Camera::Stop() {
  if (state_ != State::kStreaming)
    return;
  DoStop();
  state_ = State::kOpen;
}

void Camera::Close() {
  Stop();
  if (state_ != State::kOpen)
    return;
  DoClose();
  state_ = State::kClosed;
}

}  // namespace skyloc::drivers
