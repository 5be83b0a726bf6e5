// A scripted V4L2 capture device under the real V4L2 driver (through V4l2Io): used by
// the driver's fault tests and as an always-available instance of the camera compliance
// suite. Its clock moves only when the driver polls or sleeps, so tests take no wall time.
#pragma once

#include <linux/videodev2.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "skyloc/drivers/v4l2_io.h"

namespace skyloc::drivers::testing {

// A capture device as the V4L2 API describes it, with knobs a test turns between calls.
class FakeV4l2Device final : public V4l2Io {
 public:
  // --- the script ---
  std::string node = "/dev/video0";
  std::vector<std::uint32_t> formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_GREY};
  Nanoseconds frame_interval = std::chrono::milliseconds(40);
  std::uint32_t max_width = 64;
  std::uint32_t max_height = 48;
  bool unplugged = false;            // open: ENOENT; ioctls on open descriptors: ENODEV
  bool stalled = false;              // streaming, but no frames
  bool spurious_wakeups = false;     // poll() says ready every 10 ms, but there is no frame
  std::uint32_t skip_sequences = 0;  // the driver lost frames before the next one
  bool next_frame_error = false;     // V4L2_BUF_FLAG_ERROR on the next frame
  bool next_frame_short = false;     // bytesused half the image on the next frame
  // The next frame carries the previous frame's sequence number again (vivid did, in a
  // guest starved of CPU: the HIL VM, 2026-11-28).
  bool repeat_last_sequence = false;
  // --- what happened ---
  int opens = 0;
  int streamons = 0;
  Nanoseconds slept{0};

  int Open(const char* path, int) override {
    if (unplugged || node != path) {
      errno = ENOENT;
      return -1;
    }
    const int fd = ::memfd_create("fake-v4l2", MFD_CLOEXEC);
    if (fd < 0)
      return -1;
    ++opens;
    buffers_ = 0;
    streaming_ = false;
    queue_head_ = queue_size_ = 0;
    return fd;
  }

  int Ioctl(int fd, unsigned long request, void* arg) override {
    if (unplugged)
      return Fail(ENODEV);
    switch (request) {
      case VIDIOC_QUERYCAP: {
        auto* cap = static_cast<v4l2_capability*>(arg);
        *cap = {};
        std::strcpy(reinterpret_cast<char*>(cap->driver), "fake");
        std::strcpy(reinterpret_cast<char*>(cap->card), "Fake Cam");
        cap->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
        cap->capabilities = cap->device_caps | V4L2_CAP_DEVICE_CAPS;
        return 0;
      }
      case VIDIOC_ENUM_FMT: {
        auto* desc = static_cast<v4l2_fmtdesc*>(arg);
        if (desc->index >= formats.size())
          return Fail(EINVAL);
        desc->pixelformat = formats[desc->index];
        return 0;
      }
      case VIDIOC_S_FMT: {
        v4l2_pix_format& pix = static_cast<v4l2_format*>(arg)->fmt.pix;
        if (std::find(formats.begin(), formats.end(), pix.pixelformat) == formats.end())
          pix.pixelformat = formats[0];
        pix.width = std::min(pix.width, max_width);  // a small sensor: the driver adjusts
        pix.height = std::min(pix.height, max_height);
        pix.bytesperline = pix.width * (pix.pixelformat == V4L2_PIX_FMT_YUYV ? 2 : 1) + 8;
        pix.sizeimage = pix.bytesperline * pix.height;
        format_ = pix;
        return 0;
      }
      case VIDIOC_G_PARM: {
        auto* parm = static_cast<v4l2_streamparm*>(arg);
        parm->parm.capture.capability = V4L2_CAP_TIMEPERFRAME;
        parm->parm.capture.timeperframe = timeperframe_;
        return 0;
      }
      case VIDIOC_S_PARM:
        timeperframe_ = static_cast<v4l2_streamparm*>(arg)->parm.capture.timeperframe;
        return 0;
      case VIDIOC_REQBUFS: {
        auto* req = static_cast<v4l2_requestbuffers*>(arg);
        buffers_ = std::min(req->count, 8u);
        buffer_size_ = (format_.sizeimage + 4095u) / 4096u * 4096u;
        if (::ftruncate(fd, static_cast<off_t>(buffers_ * buffer_size_)) != 0)
          return -1;
        req->count = buffers_;
        return 0;
      }
      case VIDIOC_QUERYBUF: {
        auto* buf = static_cast<v4l2_buffer*>(arg);
        if (buf->index >= buffers_)
          return Fail(EINVAL);
        buf->length = buffer_size_;
        buf->m.offset = buf->index * buffer_size_;
        return 0;
      }
      case VIDIOC_QBUF: {
        const auto* buf = static_cast<v4l2_buffer*>(arg);
        if (buf->index >= buffers_ || IsQueued(buf->index))
          return Fail(EINVAL);
        queue_[(queue_head_ + queue_size_++) % queue_.size()] = buf->index;
        return 0;
      }
      case VIDIOC_STREAMON:
        streaming_ = true;
        sequence_ = 0;
        ++streamons;
        return 0;
      case VIDIOC_STREAMOFF:
        streaming_ = false;
        queue_head_ = queue_size_ = 0;
        return 0;
      case VIDIOC_DQBUF: {
        if (!streaming_ || queue_size_ == 0 || !frame_ready_)
          return Fail(EAGAIN);
        frame_ready_ = false;
        auto* buf = static_cast<v4l2_buffer*>(arg);
        buf->index = queue_[queue_head_];
        queue_head_ = (queue_head_ + 1) % queue_.size();
        --queue_size_;
        sequence_ += skip_sequences;
        skip_sequences = 0;
        if (repeat_last_sequence && sequence_ > 0)
          --sequence_;
        repeat_last_sequence = false;
        buf->sequence = sequence_++;
        buf->timestamp.tv_sec = static_cast<time_t>(now_.count() / 1'000'000'000);
        buf->timestamp.tv_usec = static_cast<suseconds_t>(now_.count() % 1'000'000'000 / 1000);
        buf->flags =
            V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC | (next_frame_error ? V4L2_BUF_FLAG_ERROR : 0);
        buf->bytesused = next_frame_short ? format_.sizeimage / 2 : format_.sizeimage;
        next_frame_error = false;
        next_frame_short = false;
        // Pixel (x, y) of frame s holds (s + x + y) mod 256.
        // Row by row from a stack buffer: the fake allocates nothing per frame either, so
        // the compliance suite can prove the driver's Capture() allocation-free.
        std::array<std::uint8_t, 256> row{};
        for (std::uint32_t y = 0; y < format_.height; ++y) {
          for (std::uint32_t x = 0; x < format_.bytesperline; ++x)
            row[x] = static_cast<std::uint8_t>(buf->sequence + x + y);
          const auto offset =
              static_cast<off_t>(buf->index * buffer_size_ + y * format_.bytesperline);
          if (::pwrite(fd, row.data(), format_.bytesperline, offset) !=
              static_cast<ssize_t>(format_.bytesperline))
            return -1;
        }
        return 0;
      }
      default:
        return Fail(ENOTTY);
    }
  }

  int Poll(int, int timeout_ms) override {
    if (unplugged)
      return 1;  // POLLERR: the next ioctl reports ENODEV
    const Nanoseconds timeout = std::chrono::milliseconds(timeout_ms);
    if (spurious_wakeups) {
      now_ += std::chrono::milliseconds(10);
      return 1;
    }
    if (!streaming_ || queue_size_ == 0 || stalled || frame_interval > timeout) {
      now_ += timeout;
      return 0;
    }
    now_ += frame_interval;
    frame_ready_ = true;
    return 1;
  }
  Nanoseconds Now() override { return now_; }
  void SleepFor(Nanoseconds d) override {
    now_ += d;
    slept += d;
  }

 private:
  static int Fail(int e) {
    errno = e;
    return -1;
  }

  Nanoseconds now_ = std::chrono::seconds(10);
  v4l2_pix_format format_{};
  v4l2_fract timeperframe_{1, 30};
  std::uint32_t buffers_ = 0;
  std::uint32_t buffer_size_ = 0;
  bool IsQueued(std::uint32_t index) const {
    for (std::size_t i = 0; i < queue_size_; ++i)
      if (queue_[(queue_head_ + i) % queue_.size()] == index)
        return true;
    return false;
  }

  std::array<std::uint32_t, 8> queue_{};  // FIFO of queued buffer indices
  std::size_t queue_head_ = 0;
  std::size_t queue_size_ = 0;
  bool streaming_ = false;
  bool frame_ready_ = false;
  std::uint32_t sequence_ = 0;
};

}  // namespace skyloc::drivers::testing
