// The camera's simulated twin: frames from a FrameSource, timing from an injected Clock,
// and scripted faults that make it misbehave the way real cameras do, reported through
// the same Status codes and CameraCounters as the V4L2 driver:
//
//   fault          what Capture() does                                    counters
//   kDrop          skips `count` source frames; the sequence jumps        dropped += count
//   kStall         `count` calls return kDeadlineExceeded, then resumes   errors
//   kDisconnect    `count` calls return kUnavailable (device gone), then  errors, restarts += 1
//                  the camera "reopens" and resumes
//   kCorruptSize   one call returns kDataLoss (the frame's byte count     errors
//                  does not match the format); the sequence advances
//
// Capture() never blocks (unless `paced`): a stall is reported at once rather than after
// `timeout`, so tests of the fault paths take no wall time. Timestamps: a source that
// defines its frames' times (a trajectory) stamps them; otherwise they are CLOCK-like:
// each frame is stamped max(clock.Now(), previous + frame_interval), so under a
// ManualClock they are spaced exactly one interval apart and under a real clock they
// never run ahead of it by more than one interval.
//
// Frame sequence numbers are the source's frame indices: they keep increasing across
// Stop()/Start(), and start again at 0 after Open().
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/frame_source.h"
#include "skyloc/dsp/image.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

struct CameraFault {
  enum class Kind : std::uint8_t { kDrop, kStall, kDisconnect, kCorruptSize };
  Kind kind = Kind::kDrop;
  std::uint64_t at_frame = 0;  // source frame index at which the fault strikes
  std::uint32_t count = 1;     // frames dropped, or Capture() calls stalled / unplugged
};

struct SimulatedCameraConfig {
  const char* name = nullptr;  // nullptr: the source's name()
  int width = 320;
  int height = 240;
  dsp::PixelFormat format = dsp::PixelFormat::kGrey8;
  Nanoseconds frame_interval{33'333'333};  // 30 fps
  std::uint64_t frame_count = 0;           // 0: the source's; else kOutOfRange after this many
  // Deliver frames in real time, one frame_interval apart from Start(), as a camera does
  // (Capture() sleeps until the frame is due). For a live run on a MonotonicClock.
  bool paced = false;
};

class SimulatedCamera final : public Camera {
 public:
  static constexpr std::size_t kMaxFaults = 16;

  // `source` and `clock` must outlive the camera. Nothing here can fail: Open() checks
  // the configuration.
  SimulatedCamera(const SimulatedCameraConfig& config, FrameSource* source, const Clock* clock);
  ~SimulatedCamera() override { Close(); }

  // Schedules a fault. kResourceExhausted once kMaxFaults are scheduled.
  Status InjectFault(const CameraFault& fault);
  void ClearFaults() { fault_count_ = 0; }

 private:
  Status DoOpen() override;
  Status DoStart() override;
  Result<Frame> DoCapture(Nanoseconds timeout) override;
  void DoStop() override;
  void DoClose() override;

  struct ScheduledFault {
    CameraFault fault;
    bool fired = false;
  };
  // The scheduled fault, not yet fired, striking at source frame `index`, or nullptr.
  ScheduledFault* FaultAt(std::uint64_t index);

  SimulatedCameraConfig config_;
  FrameSource* source_;
  std::uint64_t frame_count_ = 0;  // config's or source's, 0 = endless
  const Clock* clock_;
  FixedArray<std::uint8_t> pixels_;
  std::size_t stride_ = 0;

  std::array<ScheduledFault, kMaxFaults> faults_{};
  std::size_t fault_count_ = 0;

  std::uint64_t next_index_ = 0;      // next source frame to deliver
  std::uint32_t stalls_left_ = 0;     // of the stall currently in progress
  std::uint32_t unplugged_left_ = 0;  // of the disconnect currently in progress
  bool reconnect_pending_ = false;    // a disconnect ended: the next call "reopens"
  std::uint64_t start_index_ = 0;     // paced: the frame and time of the last Start()
  Nanoseconds start_time_{0};
  bool have_timestamp_ = false;
  Nanoseconds last_timestamp_{0};
};

}  // namespace skyloc::drivers
