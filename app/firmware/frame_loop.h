// The frame loop shared by teach, repeat, replay and the demo: capture -> pipeline ->
// status output -> sink, once per frame, until a signal, the end of the source or a
// fatal error. Everything it touches was allocated before it starts; the loop itself
// allocates nothing (tests/app/frame_loop_test.cpp arms the allocation counter around it).
#pragma once

#include <cstdint>
#include <cstdio>

#include "firmware/button.h"
#include "firmware/device_report.h"
#include "firmware/frame_recorder.h"
#include "firmware/pipeline.h"
#include "firmware/route_db.h"
#include "skyloc/drivers/attitude_source.h"
#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/status_output.h"

namespace skyloc::firmware {

// kRecord: frames only go to LoopOptions::recorder (`skyloc record`), nothing is described.
// kWaitForButton: the same, until the teach button is pressed (repeat without a route).
enum class LoopMode : std::uint8_t { kTeach, kRepeat, kRecord, kWaitForButton };

// Receives every frame's result. Implementations must not allocate.
class FrameSink {
 public:
  virtual ~FrameSink() = default;
  // `route_frames`: teach only, frames recorded so far.
  virtual void OnFrame(LoopMode mode, const FrameResult& result, std::uint64_t route_frames) = 0;
};

// Fans one frame out to two sinks (the outputs and a progress line, say). The JSON lines
// and the other outputs: firmware/output_publisher.h.
class TeeSink final : public FrameSink {
 public:
  TeeSink(FrameSink* a, FrameSink* b) : a_(a), b_(b) {}
  void OnFrame(LoopMode mode, const FrameResult& r, std::uint64_t n) override {
    if (a_ != nullptr)
      a_->OnFrame(mode, r, n);
    if (b_ != nullptr)
      b_->OnFrame(mode, r, n);
  }

 private:
  FrameSink* a_;
  FrameSink* b_;
};

struct LoopOptions {
  LoopMode mode = LoopMode::kRepeat;
  std::uint64_t max_frames = 0;  // 0: until a signal or the end of the source
  bool paced = false;            // sleep so frames are processed at their timestamps' pace
  Nanoseconds capture_timeout = std::chrono::seconds(1);
  // Capture errors in a row (timeouts, corrupt frames) before the loop gives up.
  int max_consecutive_errors = 30;
  // The source is a recording (a dataset): a frame it cannot deliver as recorded (another
  // size or format, kDataLoss) or the pipeline rejects is fatal at once, the error naming
  // the file. A live camera's corrupt frame is skipped and counted instead; the next one
  // may be fine, while a recording's frame stays wrong.
  bool recorded = false;
  // How long a camera may stay unavailable (unplugged; the V4L2 driver reopens it with
  // backoff) before the loop gives up; 0: at once.
  Nanoseconds reconnect_timeout = std::chrono::seconds(30);
  // --record: every captured frame (with its attitude when there is one) is offered to the
  // recorder, which copies it and never blocks; null: no recording.
  FrameRecorder* recorder = nullptr;
  // The teach button: before each frame the status output's pending edges go through this
  // debouncer, and an accepted press ends the loop (LoopSummary::button_pressed); its
  // clock is the pipeline's, which must be the one the edges are stamped with. null: no
  // button.
  ButtonDebouncer* button = nullptr;
  // Teach: the status lines show that a route is being taught (see kTeachingPeriod),
  // where a plain teach leaves them in the safe state.
  bool show_teaching = false;
  // SIGUSR1 prints their counters' table after the latency table; null: no table.
  const DeviceReport* devices = nullptr;
};

// While teaching with show_teaching, the SEARCHING indicator is shown for the first half
// of every period and the lines are safe for the second: per-state, the SEARCHING line
// blinks at 0.5 Hz (repeat never blinks it); blink encoding, one 500 ms flash every 2 s
// (LOST flashes 100 ms, SEARCHING blinks at 1 Hz).
inline constexpr Nanoseconds kTeachingPeriod = std::chrono::seconds(2);

struct LoopSummary {
  std::uint64_t frames = 0;            // frames through the pipeline
  std::uint64_t capture_errors = 0;    // timeouts and corrupt frames skipped
  std::uint64_t state_frames[3] = {};  // frames shown as LOST, SEARCHING, LOCALISED
  bool end_of_source = false;          // a finite source (dataset) ran out
  bool stopped = false;                // SIGINT/SIGTERM or RequestStop()
  // [attitude]: frames described as if level because the source had no attitude for them
  // (none yet, stale, or the IMU gone); each outage is warned about once on stderr.
  std::uint64_t attitude_missing = 0;
  // Frames described without sky contrast (lens cap, saturated sensor, fog): never matched.
  std::uint64_t frames_without_contrast = 0;
  bool button_pressed = false;  // LoopOptions::button accepted a press: the loop ended there
};

// Runs until stopped. `status` and `sink` may be null; `route` is required for teach.
// Time is the pipeline's clock (Pipeline::clock()): the reconnect time, pacing, the
// latencies and the status lines' blink are measured with it (tests pass a ManualClock
// their camera advances, so time-outs and blink edges are exact, not timed).
//
// The status lines move with time, not with frames: while waiting for a frame (and while
// pacing) the loop wakes at the lines' next change (StatusOutput::NextChange, and the
// teaching indicator's half periods) and applies it, so a blink faster than the frames
// does not alias and a flash shorter than the gap between two frames still shows. A
// wake-up is a Capture() with the time left to the edge as its time-out (a time-out is
// not a camera error, CameraCounters); the capture time-out still runs from the first call.
// A fatal error (the camera gone for good, the route database unwritable) is returned;
// the caller then flushes what it has and drives the status lines to the safe state.
// `attitude` (may be null) gives each frame's roll and pitch when the pipeline uses them.
Status RunFrameLoop(drivers::Camera& camera, drivers::StatusOutput* status, Pipeline& pipeline,
                    RouteDbWriter* route, FrameSink* sink, const LoopOptions& options,
                    LoopSummary* summary, drivers::AttitudeSource* attitude = nullptr);

}  // namespace skyloc::firmware
