// Each frame's localisation to the configured outputs ([output], docs/OUTPUTS.md).
// OnFrame() builds the frame's message once (its fields and its JSON line,
// FormatJsonLine) and queues it by value on a fixed lock-free queue, which the publisher
// thread empties into every output, off the frame loop. When the queue is full, by
// PublishMode:
//   kDropWhenFull (a live camera): the frame is dropped for every output and counted: the
//     camera does not wait for a reader.
//   kWaitWhenFull (a recording or the simulator: no deadline, and every line is wanted):
//     the frame loop waits for room, so no frame is lost.
#pragma once

#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <semaphore>
#include <span>
#include <thread>

#include "firmware/device_report.h"
#include "firmware/frame_loop.h"
#include "firmware/route_db.h"
#include "skyloc/drivers/localisation_output.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/spsc_queue.h"

namespace skyloc::firmware {

// The one JSON line of a frame, its newline included, into `out`; returns its length
// (0 when it does not fit). Every line starts with "schema" (drivers::kLocalisationSchema):
//   repeat: {"schema":1,"frame":12,"timestamp":0.400000,"best_index":10,"route_length":300,
//            "distance_m":5.00,"uniqueness":0.4100,"confidence":0.5900,"state":"SEARCHING",
//            "heading_deg":-12.30,"heading_confidence":0.9412,"heading_surf_deg":-12.10,
//            "heading_surf_inliers":41,"latency_us":812}
//   teach:  {"schema":1,"frame":12,"timestamp":0.400000,"route_frames":13,"threshold":97,
//            "sky_fraction":0.4100,"latency_us":650}
//   record, waiting for the teach button: {"schema":1,"frame":12,"timestamp":0.4,"latency_us":9}
// best_index is null until the matcher has a match; distance_m is null without a match or
// when the route's frames have no poses; the heading fields are null without a match or
// when the route has no horizon strips (FrameResult says what they mean).
std::size_t FormatJsonLine(LoopMode mode, const FrameResult& r, std::uint64_t route_frames,
                           double distance_m, char* out, std::size_t size);

// The frame's message: its fields and its JSON line. `route_frames`: teach, frames taught
// so far; repeat, the route's length. `distance_m`: along the route to the match (NaN:
// unknown).
void BuildLocalisationMessage(LoopMode mode, const FrameResult& r, std::uint64_t route_frames,
                              double distance_m, drivers::LocalisationMessage* message);

// How far along the route each taught frame is: the sum of the horizontal distances
// between consecutive frames' poses, from the first frame. NaN from the first frame
// without a pose on. Sized at start-up; recomputed (without allocating) when the route
// changes length, as the teach button's re-teach does.
class RouteProgress {
 public:
  Status Allocate(std::size_t capacity) { return along_m_.Allocate(capacity); }
  // Frame path: brings the table up to date with `route` (null: no route).
  void Follow(const RouteFrames* route);
  std::uint64_t length() const { return length_; }
  double DistanceTo(std::int64_t index) const;

 private:
  FixedArray<double> along_m_;
  std::size_t length_ = 0;
};

struct OutputPublisherCounters {
  std::uint64_t frames = 0;         // offered by the frame loop
  std::uint64_t queue_dropped = 0;  // the queue was full: no output got the frame
};

enum class PublishMode : std::uint8_t { kDropWhenFull, kWaitWhenFull };

class OutputPublisher final : public FrameSink {
 public:
  static constexpr std::size_t kQueueCapacity = 64;

  OutputPublisher() = default;
  ~OutputPublisher() override;
  OutputPublisher(const OutputPublisher&) = delete;
  OutputPublisher& operator=(const OutputPublisher&) = delete;

  // `outputs` are open and outlive the publisher's Stop(). `route` (repeat: the route the
  // matches index; may be null) gives the length and the distance along it; `capacity` is
  // the most frames it can hold. Allocates the queue and starts the thread.
  Status Start(std::span<drivers::LocalisationOutput* const> outputs, const RouteFrames* route,
               std::size_t route_capacity, PublishMode mode);
  // The devices whose counters follow the first frame's line and then the first frame of
  // every second of the frames' time, as a record of their own in the JSON outputs
  // (DeviceReport::FormatJson; null: none). Read on the frame loop's thread; they must
  // outlive the publisher's use.
  void set_devices(const DeviceReport* devices) { devices_ = devices; }
  // Frame path: allocates nothing; never blocks in kDropWhenFull.
  void OnFrame(LoopMode mode, const FrameResult& result, std::uint64_t route_frames) override;
  // Publishes what is queued and stops the thread. Safe to call twice.
  void Stop();
  bool running() const { return running_; }
  OutputPublisherCounters counters() const;

 private:
  using Queue = SpscQueue<drivers::LocalisationMessage, kQueueCapacity>;
  void PublishLoop();

  std::span<drivers::LocalisationOutput* const> outputs_;
  const RouteFrames* route_ = nullptr;
  RouteProgress progress_;
  PublishMode mode_ = PublishMode::kDropWhenFull;
  const DeviceReport* devices_ = nullptr;
  Nanoseconds devices_due_ = Nanoseconds::min();  // frame time of the next devices record
  bool running_ = false;
  std::unique_ptr<Queue> queue_;
  std::unique_ptr<drivers::LocalisationMessage> building_;  // the frame path's message
  std::unique_ptr<drivers::LocalisationMessage> popped_;    // the publisher thread's
  std::counting_semaphore<> queued_{0};  // one release per queued message, one for Stop()
  std::atomic<std::uint64_t> frames_{0}, queue_dropped_{0};
  std::atomic<std::uint8_t> last_state_{0};
  std::thread thread_;
};

}  // namespace skyloc::firmware
