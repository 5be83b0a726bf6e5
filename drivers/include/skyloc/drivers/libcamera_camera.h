// A camera through libcamera (Raspberry Pi CSI cameras, UVC, vimc). Built when
// SKYLOC_WITH_LIBCAMERA. Written against Debian 12's libcamera 0.0.3; the API notes
// in docs/DRIVERS.md list what changed in later versions.
//
// Open():  starts a CameraManager, picks the camera by id (or the first), acquires it,
//          configures one stream (Viewfinder, or Raw) in the first format skyloc reads
//          (R8, YUYV, RGB888/BGR888), allocates the buffers with a FrameBufferAllocator,
//          mmaps every dmabuf plane once and creates one Request per buffer.
// Start(): camera->start() with the frame rate (FrameDurationLimits, when the camera lists
//          that control; otherwise it says so once on stderr and streams at the camera's
//          own rate) and the exposure, queues every request.
// Capture(): requeues the request handed out last time (Request::ReuseBuffers), waits on
//          an eventfd (poll with the timeout) for a completed request, which libcamera's
//          thread put into a fixed-size SPSC queue (the callback does nothing else:
//          no allocation, no lock, no work on libcamera's thread).
// Stop():  sets `stopping` first so nothing is queued any more (queuing while the camera
//          stops crashed libcamera in the VM study), camera->stop() (cancels pending
//          requests, which still come through the queue), then drains the queue.
// Unplug:  libcamera's `disconnected` signal, or no frame for `stall_timeout` (without
//          udevd libcamera never learns that a device went away: its requests just stop
//          completing), makes the camera *lost*: Capture() returns kFailedPrecondition
//          naming the camera, now and on every later call, and skyloc exits so that its
//          service restarts it (config/skyloc.service: Restart=on-failure), and the new
//          process finds the camera once it is back. It cannot reopen the camera itself,
//          unlike the V4L2 driver: libcamera 0.0.3 aborts the process when a camera whose
//          device has gone is stopped (PipelineHandler::stop asserts that its requests
//          completed), crashes when the manager is stopped under it, and allows one
//          CameraManager per process (measured in the VM, vimc unbound; docs/DRIVERS.md).
//          So a lost camera is never stopped or released: Close() lets go of libcamera's
//          objects without destroying them, and the process can exit cleanly.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/mapped_buffer.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/spsc_queue.h"
#include "skyloc/platform/status.h"
#include "skyloc/platform/unique_fd.h"

namespace libcamera {
class Camera;
class CameraConfiguration;
class CameraManager;
class FrameBufferAllocator;
class Request;
class Stream;
}  // namespace libcamera

namespace skyloc::drivers {

struct LibcameraCameraConfig {
  char camera_id[128] = "";  // as `cam -l` prints it; empty or "first": the first camera
  // The rate through the FrameDurationLimits control, when the camera lists it.
  CaptureFormat capture;
  bool raw = false;                // StreamRole::Raw instead of Viewfinder
  std::uint32_t buffer_count = 4;  // 1..kMaxRequests (the pipeline may raise its minimum)
  std::int32_t exposure_us = 0;    // > 0: manual exposure (AeEnable off), if supported
  // No frame for this long while streaming: the camera is lost (see Unplug above).
  Nanoseconds stall_timeout{std::chrono::seconds(2)};
};

class LibcameraCamera final : public Camera {
 public:
  static constexpr std::size_t kMaxRequests = 8;

  // `clock` (nullptr: SystemMonotonicClock()) times Capture()'s timeout and the stall; it
  // must outlive the camera. Frames carry libcamera's own CLOCK_MONOTONIC timestamps.
  explicit LibcameraCamera(const LibcameraCameraConfig& config, const Clock* clock = nullptr);
  ~LibcameraCamera() override;

  // The frame rate set at Start() (0 when fps is 0 or the camera has no
  // FrameDurationLimits control).
  double fps() const { return fps_; }
  // Completed requests that did not fit the queue (cannot happen while the queue holds
  // every request; counted so a test can prove it).
  std::uint64_t queue_overflows() const { return overflows_.load(std::memory_order_relaxed); }

 private:
  Status DoOpen() override;
  Status DoStart() override;
  Result<Frame> DoCapture(Nanoseconds timeout) override;
  void DoStop() override;
  void DoClose() override;

  Status Configure();
  Status QueueRequest(libcamera::Request* request);
  // libcamera's thread: hands the request over, nothing else.
  void OnRequestCompleted(libcamera::Request* request);
  // libcamera's thread: the camera was unplugged. Flags it and wakes Capture().
  void OnDisconnected();
  // The camera is gone (`why`): from now on Capture() returns the error this returns.
  Status Lost(const char* why);

  LibcameraCameraConfig config_;
  const Clock* clock_;
  std::unique_ptr<libcamera::CameraManager> manager_;
  std::shared_ptr<libcamera::Camera> camera_;
  std::unique_ptr<libcamera::CameraConfiguration> configuration_;
  std::unique_ptr<libcamera::FrameBufferAllocator> allocator_;
  libcamera::Stream* stream_ = nullptr;
  std::array<std::unique_ptr<libcamera::Request>, kMaxRequests> requests_;
  std::array<MappedBuffer, kMaxRequests> mappings_;
  std::array<std::size_t, kMaxRequests> plane_offsets_{};
  std::size_t request_count_ = 0;
  std::size_t stride_ = 0;
  std::size_t frame_bytes_ = 0;
  double fps_ = 0;
  bool told_rate_not_set_ = false;
  bool acquired_ = false;
  bool started_ = false;
  bool lost_ = false;
  char lost_why_[64] = "";
  Nanoseconds last_progress_{0};  // when streaming started or the last frame arrived

  UniqueFd completed_fd_;  // eventfd: counts requests pushed into completed_
  SpscQueue<libcamera::Request*, 16> completed_;
  std::atomic<bool> stopping_{false};
  std::atomic<bool> disconnected_{false};
  std::atomic<std::uint64_t> overflows_{0};
  libcamera::Request* held_ = nullptr;  // the request whose buffer the last Frame shows
  // libcamera numbers frames from 0 again after each start(); ours keep increasing.
  std::uint64_t sequence_base_ = 0;
  std::uint64_t next_sequence_ = 0;
  bool have_sequence_ = false;
};

}  // namespace skyloc::drivers
