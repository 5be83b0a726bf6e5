// A V4L2 capture device (USB UVC cameras, CSI bridges with a V4L2 video node, vivid, vimc).
// Built when SKYLOC_WITH_V4L2.
//
// Open():  finds the device (a path, or "driver:card" as VIDIOC_QUERYCAP reports them,
//          by scanning /dev/video*), checks it captures and streams, negotiates the pixel
//          format (GREY, then YUYV, then RGB24/BGR24; otherwise the error lists what the
//          device offers), sets the frame rate (VIDIOC_S_PARM, when the driver allows
//          it), and allocates and mmaps `buffer_count` buffers: the only allocation.
// Start(): queues every buffer, STREAMON.
// Capture(): requeues the buffer handed out last time, poll()s with the timeout,
//          dequeues one buffer. The timestamp is the buffer's (CLOCK_MONOTONIC when the
//          driver sets V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC, else the time of dequeueing);
//          gaps in the driver's sequence numbers count as drops.
// Faults:  ENODEV/EIO/... or a stream stalled for `recovery.stall_timeout` close the
//          device; Capture() then reopens it with exponential backoff (StreamRecovery),
//          returning kUnavailable while it is gone, and counts each successful reopen in
//          counters().restarts. Frame sequence numbers stay increasing across restarts.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/mapped_buffer.h"
#include "skyloc/drivers/stream_recovery.h"
#include "skyloc/drivers/v4l2_io.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"
#include "skyloc/platform/unique_fd.h"

namespace skyloc::drivers {

struct V4l2CameraConfig {
  char device[128] = "/dev/video0";  // "/dev/videoN", or "driver:card" (e.g. "vivid:vivid")
  CaptureFormat capture;             // the rate through VIDIOC_S_PARM, when the driver allows it
  std::uint32_t buffer_count = 4;    // 2..kMaxBuffers
  StreamRecoveryConfig recovery;
};

class V4l2Camera final : public Camera {
 public:
  static constexpr std::uint32_t kMaxBuffers = 8;

  // `io` (default: the real system calls) must outlive the camera.
  explicit V4l2Camera(const V4l2CameraConfig& config, V4l2Io* io = nullptr);
  ~V4l2Camera() override { Close(); }

  // The /dev/video* node actually opened (resolved from a driver:card name).
  const char* device_path() const { return path_; }
  // The frame rate the driver accepted (0 when it does not support setting it).
  double fps() const { return fps_; }
  std::size_t frame_bytes() const { return frame_bytes_; }
  const StreamRecovery& recovery() const { return recovery_; }

 private:
  Status DoOpen() override;
  Status DoStart() override;
  Result<Frame> DoCapture(Nanoseconds timeout) override;
  void DoStop() override;
  void DoClose() override;

  Status OpenDevice();      // find, open, QUERYCAP, format, frame rate, buffers
  Status StartStreaming();  // QBUF all, STREAMON
  void CloseDevice();       // STREAMOFF, unmap, REQBUFS 0, close
  Status Requeue();         // the buffer handed out by the previous Capture()
  // Handles a failed ioctl/poll: device loss starts recovery, anything else is returned.
  Status Fail(int saved_errno, const char* what, Nanoseconds now);
  Status Recover(Nanoseconds now);

  int Xioctl(int fd, unsigned long request, void* arg);

  V4l2CameraConfig config_;
  V4l2Io* io_;
  StreamRecovery recovery_;
  Status last_reopen_error_;  // why the last reopen failed, for the kUnavailable message
  UniqueFd fd_;
  char path_[128] = {};
  std::array<MappedBuffer, kMaxBuffers> buffers_;
  std::uint32_t buffer_count_ = 0;
  std::uint32_t fourcc_ = 0;
  std::size_t stride_ = 0;
  std::size_t frame_bytes_ = 0;
  double fps_ = 0;
  bool streaming_ = false;
  int held_buffer_ = -1;  // index of the buffer the last Frame points into
  // Sequence numbers restart at 0 after STREAMON; frames keep increasing numbers across
  // restarts through this offset.
  std::uint64_t sequence_base_ = 0;
  std::uint64_t next_sequence_ = 0;  // the sequence we expect next (drop detection)
  bool have_sequence_ = false;
};

}  // namespace skyloc::drivers
