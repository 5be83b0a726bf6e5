// The camera interface every source of frames implements: V4L2, libcamera, the simulated
// camera, dataset replay. Public non-virtual methods check the call order once, here, so
// every implementation behaves the same way to the pipeline; implementations override
// the private Do* hooks only.
//
//   Closed --Open()--> Open --Start()--> Streaming --Stop()--> Open --Close()--> Closed
//
// Buffers are allocated in Open() (sized from the configuration); Capture() hands out a
// view of one of them that stays valid until the next Capture() or Stop(). Capture()
// allocates nothing, with one exception on purpose: dataset replay (DatasetCamera), a
// laptop tool, decodes a file in each Capture() and so allocates.
#pragma once

#include <cstdint>
#include <optional>

#include "skyloc/dsp/image.h"
#include "skyloc/dsp/imu.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// Where the camera was, when the source knows it (simulator, recorded datasets).
struct Pose {
  double x_m = 0, y_m = 0, z_m = 0;
  double roll_deg = 0, pitch_deg = 0, yaw_deg = 0;
};

struct Frame {
  dsp::ImageView image;
  std::uint64_t sequence = 0;  // counts every frame the source produced, dropped ones too
  Nanoseconds timestamp{0};    // CLOCK_MONOTONIC time the frame was captured
  std::optional<Pose> pose;
  // The roll and pitch recorded with the frame (a dataset's columns), for
  // FrameAttitudeSource; live cameras leave it empty (the IMU is a device of its own).
  std::optional<dsp::Attitude> attitude;
};

// The frame size and rate a camera is asked for, held as it is by every live camera's
// config (and by the configuration's [camera] section). What the camera granted is in
// info() (the size) and the driver's fps().
struct CaptureFormat {
  int width = 640;
  int height = 480;
  double fps = 30.0;  // 0: leave the camera's frame rate alone

  bool operator==(const CaptureFormat&) const = default;
};

struct CameraInfo {
  char name[64] = {};  // e.g. "v4l2:/dev/video0", "sim:city"
  int width = 0;
  int height = 0;
  dsp::PixelFormat format = dsp::PixelFormat::kGrey8;
};

// Health counters every camera keeps (the simulated twin too); the session prints them
// with the other devices' (firmware/device_report.h).
struct CameraCounters {
  std::uint64_t frames = 0;    // frames delivered by Capture()
  std::uint64_t dropped = 0;   // gaps in the sequence numbers
  std::uint64_t restarts = 0;  // times the device was closed and reopened after a fault
  // Capture() calls that returned an error other than a time-out or the end of a finite
  // source. A time-out is not one: how long to wait is the caller's choice (the frame loop
  // wakes early to move the status lines' blink, and counts a frame that did not come in
  // time itself, LoopSummary).
  std::uint64_t errors = 0;
};

class Camera {
 public:
  enum class State : std::uint8_t { kClosed, kOpen, kStreaming };

  virtual ~Camera() = default;
  Camera(const Camera&) = delete;
  Camera& operator=(const Camera&) = delete;

  Status Open();
  Status Start();
  // Waits up to `timeout` for the next frame. kDeadlineExceeded on timeout; kUnavailable
  // when the device is gone and could not be recovered; kDataLoss for a corrupt frame
  // (the next Capture() may succeed). End of a finite source (a dataset) is kOutOfRange.
  // Every error's message names the camera (info().name), so the frame loop passes it on
  // as it is; the camera compliance test checks it.
  Result<Frame> Capture(Nanoseconds timeout);
  void Stop();
  void Close();

  State state() const { return state_; }
  const CameraInfo& info() const { return info_; }
  const CameraCounters& counters() const { return counters_; }

 protected:
  Camera() = default;
  CameraInfo info_;
  CameraCounters counters_;

 private:
  virtual Status DoOpen() = 0;
  virtual Status DoStart() = 0;
  virtual Result<Frame> DoCapture(Nanoseconds timeout) = 0;
  virtual void DoStop() = 0;
  virtual void DoClose() = 0;

  State state_ = State::kClosed;
};

const char* CameraStateName(Camera::State state);

}  // namespace skyloc::drivers
