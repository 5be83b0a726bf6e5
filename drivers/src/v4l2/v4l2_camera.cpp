#include "skyloc/drivers/v4l2_camera.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <time.h>
#include <unistd.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace skyloc::drivers {
namespace {

class SystemIo final : public V4l2Io {
 public:
  int Open(const char* path, int flags) override { return ::open(path, flags); }
  int Ioctl(int fd, unsigned long request, void* arg) override { return ::ioctl(fd, request, arg); }
  int Poll(int fd, int timeout_ms) override {
    pollfd pfd{fd, POLLIN, 0};
    return ::poll(&pfd, 1, timeout_ms);
  }
  Nanoseconds Now() override { return clock_.Now(); }
  void SleepFor(Nanoseconds d) override {
    if (d <= Nanoseconds(0))
      return;
    timespec ts{};
    ts.tv_sec = static_cast<time_t>(d.count() / 1'000'000'000);
    ts.tv_nsec = static_cast<long>(d.count() % 1'000'000'000);
    while (::nanosleep(&ts, &ts) == -1 && errno == EINTR) {
    }
  }

 private:
  MonotonicClock clock_;
};

// V4L2 fourcc as text ("YUYV"), for messages.
struct FourccText {
  char text[5];
};
FourccText FourccToText(std::uint32_t fourcc) {
  FourccText t{};
  for (int i = 0; i < 4; ++i) {
    const auto c = static_cast<char>((fourcc >> (8 * i)) & 0xffu);
    t.text[i] = (c >= 32 && c < 127) ? c : '?';
  }
  return t;
}

// The formats skyloc reads, in order of preference: greyscale first (UV cameras are
// monochrome), then YUYV (its Y plane is the luminance), then packed RGB (channel mean).
struct FormatChoice {
  std::uint32_t fourcc;
  dsp::PixelFormat format;
};
constexpr FormatChoice kFormats[] = {
    {V4L2_PIX_FMT_GREY, dsp::PixelFormat::kGrey8},
    {V4L2_PIX_FMT_YUYV, dsp::PixelFormat::kYuyv},
    {V4L2_PIX_FMT_RGB24, dsp::PixelFormat::kRgb24},
    {V4L2_PIX_FMT_BGR24, dsp::PixelFormat::kBgr24},
};

std::uint32_t DeviceCaps(const v4l2_capability& cap) {
  return (cap.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? cap.device_caps : cap.capabilities;
}

bool IsCaptureDevice(const v4l2_capability& cap) {
  const std::uint32_t caps = DeviceCaps(cap);
  return (caps & V4L2_CAP_VIDEO_CAPTURE) != 0 && (caps & V4L2_CAP_STREAMING) != 0;
}

}  // namespace

V4l2Io& SystemV4l2Io() {
  static SystemIo io;
  return io;
}

// ioctl, retried when a signal interrupts it (V4L2 ioctls may block).
int V4l2Camera::Xioctl(int fd, unsigned long request, void* arg) {
  int r = 0;
  do {
    r = io_->Ioctl(fd, request, arg);
  } while (r == -1 && errno == EINTR);
  return r;
}

V4l2Camera::V4l2Camera(const V4l2CameraConfig& config, V4l2Io* io)
    : config_(config), io_(io != nullptr ? io : &SystemV4l2Io()), recovery_(config.recovery) {
  config_.device[sizeof(config_.device) - 1] = '\0';
  std::snprintf(info_.name, sizeof(info_.name), "v4l2:%.58s", config_.device);
  info_.width = config.capture.width;
  info_.height = config.capture.height;
}

Status V4l2Camera::DoOpen() {
  recovery_ = StreamRecovery(config_.recovery);
  next_sequence_ = 0;
  sequence_base_ = 0;
  have_sequence_ = false;
  Status s = OpenDevice();
  if (!s.ok())
    CloseDevice();
  return s;
}

Status V4l2Camera::OpenDevice() {
  if (config_.buffer_count < 2 || config_.buffer_count > kMaxBuffers) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "camera %s: buffer_count %u is outside 2..%u", info_.name,
                         config_.buffer_count, kMaxBuffers);
  }
  if (config_.capture.width <= 0 || config_.capture.height <= 0) {
    return Status::Error(StatusCode::kInvalidArgument, "camera %s: invalid frame size %dx%d",
                         info_.name, config_.capture.width, config_.capture.height);
  }

  // Find and open the node.
  v4l2_capability cap{};
  if (config_.device[0] == '/') {
    std::snprintf(path_, sizeof(path_), "%s", config_.device);
    const int fd = io_->Open(path_, O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
      const int saved = errno;
      return Status::FromErrno(saved,
                               "camera %s: cannot open %s (is the camera connected? list devices "
                               "with v4l2-ctl --list-devices)",
                               info_.name, path_);
    }
    fd_.reset(fd);
    if (Xioctl(fd_.get(), VIDIOC_QUERYCAP, &cap) != 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "camera %s: VIDIOC_QUERYCAP on %s (not a V4L2 device?)",
                               info_.name, path_);
    }
  } else {
    // "driver:card": the first capture node whose QUERYCAP strings match.
    const char* colon = std::strchr(config_.device, ':');
    if (colon == nullptr) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "camera device '%s' is neither a path (/dev/videoN) nor a "
                           "driver:card name (e.g. vivid:vivid, as v4l2-ctl -D prints them)",
                           config_.device);
    }
    const auto driver_len = static_cast<std::size_t>(colon - config_.device);
    const char* card = colon + 1;
    bool found = false;
    for (int n = 0; n < 64 && !found; ++n) {
      char candidate[32];
      std::snprintf(candidate, sizeof(candidate), "/dev/video%d", n);
      UniqueFd fd(io_->Open(candidate, O_RDWR | O_NONBLOCK | O_CLOEXEC));
      if (!fd.is_valid())
        continue;
      v4l2_capability c{};
      if (Xioctl(fd.get(), VIDIOC_QUERYCAP, &c) != 0 || !IsCaptureDevice(c))
        continue;
      const auto* drv = reinterpret_cast<const char*>(c.driver);
      const auto* crd = reinterpret_cast<const char*>(c.card);
      if (std::strlen(drv) == driver_len && std::strncmp(drv, config_.device, driver_len) == 0 &&
          std::strcmp(crd, card) == 0) {
        std::snprintf(path_, sizeof(path_), "%s", candidate);
        fd_ = std::move(fd);
        cap = c;
        found = true;
      }
    }
    if (!found) {
      return Status::Error(StatusCode::kNotFound,
                           "camera %s: no /dev/video* capture node has driver '%.*s' and card "
                           "'%s' (list them with v4l2-ctl --list-devices)",
                           info_.name, static_cast<int>(driver_len), config_.device, card);
    }
  }
  if (!IsCaptureDevice(cap)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "camera %s: %s is not a single-planar streaming capture device "
                         "(capabilities 0x%08x); pick the camera's capture node",
                         info_.name, path_, DeviceCaps(cap));
  }

  // Pixel format: the first of ours that the device offers.
  const FormatChoice* choice = nullptr;
  char offered[96] = {};
  std::size_t offered_len = 0;
  for (std::uint32_t i = 0; i < 64; ++i) {
    v4l2_fmtdesc desc{};
    desc.index = i;
    desc.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (Xioctl(fd_.get(), VIDIOC_ENUM_FMT, &desc) != 0)
      break;
    if (offered_len + 6 < sizeof(offered)) {
      const FourccText t = FourccToText(desc.pixelformat);
      offered_len += static_cast<std::size_t>(std::snprintf(
          offered + offered_len, sizeof(offered) - offered_len, "%s%s", i ? " " : "", t.text));
    }
    for (const FormatChoice& f : kFormats) {
      if (f.fourcc == desc.pixelformat && (choice == nullptr || &f < choice))
        choice = &f;
    }
  }
  if (choice == nullptr) {
    return Status::Error(StatusCode::kUnimplemented,
                         "camera %s: %s offers [%s]; skyloc reads GREY, YUYV, RGB3 or BGR3: set "
                         "the camera to one of them or choose another device",
                         info_.name, path_, offered);
  }
  v4l2_format fmt{};
  fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  fmt.fmt.pix.width = static_cast<std::uint32_t>(config_.capture.width);
  fmt.fmt.pix.height = static_cast<std::uint32_t>(config_.capture.height);
  fmt.fmt.pix.pixelformat = choice->fourcc;
  fmt.fmt.pix.field = V4L2_FIELD_NONE;
  if (Xioctl(fd_.get(), VIDIOC_S_FMT, &fmt) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "camera %s: VIDIOC_S_FMT %s %dx%d", info_.name,
                             FourccToText(choice->fourcc).text, config_.capture.width,
                             config_.capture.height);
  }
  if (fmt.fmt.pix.pixelformat != choice->fourcc) {
    return Status::Error(StatusCode::kUnimplemented, "camera %s: asked for %s, the driver chose %s",
                         info_.name, FourccToText(choice->fourcc).text,
                         FourccToText(fmt.fmt.pix.pixelformat).text);
  }
  info_.width = static_cast<int>(fmt.fmt.pix.width);
  info_.height = static_cast<int>(fmt.fmt.pix.height);
  info_.format = choice->format;
  fourcc_ = choice->fourcc;
  const std::size_t row_bytes = static_cast<std::size_t>(info_.width) *
                                static_cast<std::size_t>(dsp::BytesPerPixelTimes2(info_.format)) /
                                2;
  stride_ = fmt.fmt.pix.bytesperline >= row_bytes ? fmt.fmt.pix.bytesperline : row_bytes;
  frame_bytes_ = stride_ * static_cast<std::size_t>(info_.height);

  // Frame rate, where the driver lets us set it.
  fps_ = 0;
  v4l2_streamparm parm{};
  parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (Xioctl(fd_.get(), VIDIOC_G_PARM, &parm) == 0 &&
      (parm.parm.capture.capability & V4L2_CAP_TIMEPERFRAME) != 0) {
    if (config_.capture.fps > 0) {
      parm.parm.capture.timeperframe.numerator = 1000;
      parm.parm.capture.timeperframe.denominator =
          static_cast<std::uint32_t>(std::lround(config_.capture.fps * 1000.0));
      if (Xioctl(fd_.get(), VIDIOC_S_PARM, &parm) != 0) {
        const int saved = errno;
        return Status::FromErrno(saved, "camera %s: VIDIOC_S_PARM %.2f fps", info_.name,
                                 config_.capture.fps);
      }
    }
    const v4l2_fract& tpf = parm.parm.capture.timeperframe;
    fps_ = tpf.numerator != 0 ? static_cast<double>(tpf.denominator) / tpf.numerator : 0.0;
  }

  // Buffers: requested and mapped once; Capture() only queues and dequeues them.
  v4l2_requestbuffers req{};
  req.count = config_.buffer_count;
  req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  req.memory = V4L2_MEMORY_MMAP;
  if (Xioctl(fd_.get(), VIDIOC_REQBUFS, &req) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "camera %s: VIDIOC_REQBUFS %u mmap buffers", info_.name,
                             config_.buffer_count);
  }
  if (req.count < 2 || req.count > kMaxBuffers) {
    return Status::Error(StatusCode::kResourceExhausted,
                         "camera %s: the driver granted %u buffers; skyloc needs 2..%u", info_.name,
                         req.count, kMaxBuffers);
  }
  buffer_count_ = req.count;
  for (std::uint32_t i = 0; i < buffer_count_; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (Xioctl(fd_.get(), VIDIOC_QUERYBUF, &buf) != 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "camera %s: VIDIOC_QUERYBUF %u", info_.name, i);
    }
    if (buf.length < frame_bytes_) {
      return Status::Error(StatusCode::kInternal,
                           "camera %s: buffer %u has %u bytes, a frame needs %zu", info_.name, i,
                           buf.length, frame_bytes_);
    }
    if (Status s = buffers_[i].Map(fd_.get(), static_cast<off_t>(buf.m.offset), buf.length);
        !s.ok())
      return s.AddContext("camera %s: buffer %u", info_.name, i);
  }
  return Status::Ok();
}

Status V4l2Camera::StartStreaming() {
  for (std::uint32_t i = 0; i < buffer_count_; ++i) {
    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    buf.index = i;
    if (Xioctl(fd_.get(), VIDIOC_QBUF, &buf) != 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "camera %s: VIDIOC_QBUF %u", info_.name, i);
    }
  }
  int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (Xioctl(fd_.get(), VIDIOC_STREAMON, &type) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "camera %s: VIDIOC_STREAMON", info_.name);
  }
  streaming_ = true;
  held_buffer_ = -1;
  // The driver numbers frames from 0 again: continue our numbering from where it was.
  sequence_base_ = next_sequence_;
  have_sequence_ = false;
  recovery_.Started(io_->Now());
  return Status::Ok();
}

void V4l2Camera::CloseDevice() {
  if (fd_.is_valid() && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)Xioctl(fd_.get(), VIDIOC_STREAMOFF, &type);
  }
  streaming_ = false;
  held_buffer_ = -1;
  for (MappedBuffer& b : buffers_)
    b.Unmap();
  if (fd_.is_valid() && buffer_count_ > 0) {
    v4l2_requestbuffers req{};
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    (void)Xioctl(fd_.get(), VIDIOC_REQBUFS, &req);  // frees them; errors change nothing
  }
  buffer_count_ = 0;
  fd_.reset();
}

Status V4l2Camera::DoStart() {
  if (!fd_.is_valid()) {
    // Lost while stopped: reopen now, so Start() reports a missing device itself.
    Status s = OpenDevice();
    if (!s.ok()) {
      CloseDevice();
      return s;
    }
  }
  return StartStreaming();
}

void V4l2Camera::DoStop() {
  if (fd_.is_valid() && streaming_) {
    int type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)Xioctl(fd_.get(), VIDIOC_STREAMOFF, &type);  // also dequeues every buffer
  }
  streaming_ = false;
  held_buffer_ = -1;
  if (recovery_.state() != StreamRecovery::State::kStreaming) {
    // Stopped while recovering: start afresh on the next Start().
    CloseDevice();
    recovery_ = StreamRecovery(config_.recovery);
  }
}

void V4l2Camera::DoClose() {
  CloseDevice();
}

Status V4l2Camera::Fail(int saved_errno, const char* what, Nanoseconds now) {
  if (!StreamRecovery::IsDeviceLoss(saved_errno))
    return Status::FromErrno(saved_errno, "camera %s: %s", info_.name, what);
  CloseDevice();
  recovery_.DeviceLost(now);
  return Status::Error(StatusCode::kUnavailable, "camera %s: %s: %s; device lost, reopening",
                       info_.name, what, strerrordesc_np(saved_errno));
}

Status V4l2Camera::Recover(Nanoseconds now) {
  // The pipeline sized its buffers for the frames it had: a device that comes back with
  // another size or format is not the same camera, so that reopen counts as failed.
  const CameraInfo before = info_;
  Status s = OpenDevice();
  if (s.ok() && (info_.width != before.width || info_.height != before.height ||
                 info_.format != before.format)) {
    s = Status::Error(StatusCode::kFailedPrecondition,
                      "camera %s: came back as %dx%d %s, was %dx%d %s", info_.name, info_.width,
                      info_.height, dsp::PixelFormatName(info_.format), before.width, before.height,
                      dsp::PixelFormatName(before.format));
    info_ = before;
  }
  if (s.ok())
    s = StartStreaming();
  if (!s.ok()) {
    CloseDevice();
    recovery_.ReopenFailed(now);
    last_reopen_error_ = s;
    return s;
  }
  recovery_.ReopenSucceeded(now);
  ++counters_.restarts;
  return Status::Ok();
}

Status V4l2Camera::Requeue() {
  if (held_buffer_ < 0)
    return Status::Ok();
  v4l2_buffer buf{};
  buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buf.memory = V4L2_MEMORY_MMAP;
  buf.index = static_cast<std::uint32_t>(held_buffer_);
  held_buffer_ = -1;
  if (Xioctl(fd_.get(), VIDIOC_QBUF, &buf) != 0) {
    const int saved = errno;
    return Fail(saved, "VIDIOC_QBUF", io_->Now());
  }
  return Status::Ok();
}

Result<Frame> V4l2Camera::DoCapture(Nanoseconds timeout) {
  const Nanoseconds deadline = io_->Now() + timeout;
  for (;;) {
    Nanoseconds now = io_->Now();
    if (recovery_.state() == StreamRecovery::State::kFailed) {
      return Status::Error(StatusCode::kUnavailable,
                           "camera %s: gave up after %u failed reopens: check the camera's "
                           "cable and power, then restart skyloc",
                           info_.name, recovery_.consecutive_failures());
    }
    if (recovery_.state() == StreamRecovery::State::kBackingOff) {
      if (!recovery_.ReopenDue(now)) {
        if (recovery_.next_attempt() > deadline) {
          io_->SleepFor(deadline - now);
          return Status::Error(
              StatusCode::kUnavailable,
              "camera %s: device lost; next reopen attempt in %lld ms (last attempt: %s)",
              info_.name,
              static_cast<long long>((recovery_.next_attempt() - deadline).count() / 1'000'000),
              recovery_.consecutive_failures() == 0 ? "none yet" : last_reopen_error_.message());
        }
        io_->SleepFor(recovery_.next_attempt() - now);
        continue;
      }
      const Status s = Recover(now);
      if (!s.ok() && recovery_.state() == StreamRecovery::State::kFailed) {
        return Status::Error(StatusCode::kUnavailable,
                             "camera %s: gave up after %u failed reopens (last: %s): check the "
                             "camera's cable and power, then restart skyloc",
                             info_.name, recovery_.consecutive_failures(), s.message());
      }
      continue;
    }

    SKYLOC_TRY(Requeue());
    // Wait for a frame, but wake up in time to notice a stall.
    const Nanoseconds wake =
        deadline < recovery_.stall_deadline() ? deadline : recovery_.stall_deadline();
    const Nanoseconds wait = wake - now;
    const int ready = io_->Poll(fd_.get(), PollTimeoutMs(wait));
    if (ready < 0) {
      const int saved = errno;
      if (saved == EINTR)
        continue;
      return Fail(saved, "poll", io_->Now());
    }
    now = io_->Now();
    if (ready == 0) {
      if (recovery_.IsStalled(now)) {
        CloseDevice();
        recovery_.DeviceLost(now);
        return Status::Error(
            StatusCode::kUnavailable, "camera %s: no frame for %lld ms (stream stalled); reopening",
            info_.name,
            static_cast<long long>(recovery_.config().stall_timeout.count() / 1'000'000));
      }
      if (now >= deadline) {
        return Status::Error(StatusCode::kDeadlineExceeded, "camera %s: no frame within %lld ms",
                             info_.name, static_cast<long long>(timeout.count() / 1'000'000));
      }
      continue;
    }

    v4l2_buffer buf{};
    buf.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buf.memory = V4L2_MEMORY_MMAP;
    if (Xioctl(fd_.get(), VIDIOC_DQBUF, &buf) != 0) {
      const int saved = errno;
      if (saved == EAGAIN) {  // woken without a frame (spurious, or an event)
        if (now >= deadline) {
          return Status::Error(StatusCode::kDeadlineExceeded, "camera %s: no frame within %lld ms",
                               info_.name, static_cast<long long>(timeout.count() / 1'000'000));
        }
        continue;
      }
      return Fail(saved, "VIDIOC_DQBUF", now);
    }
    if (buf.index >= buffer_count_) {
      return Status::Error(StatusCode::kInternal, "camera %s: driver returned buffer %u of %u",
                           info_.name, buf.index, buffer_count_);
    }
    held_buffer_ = static_cast<int>(buf.index);
    recovery_.FrameArrived(now);

    std::uint64_t sequence = sequence_base_ + buf.sequence;
    // A frame the driver stamps with a number already given (vivid did, in a guest starved
    // of CPU) gets the next number of ours, and our numbering follows the driver's from
    // there: a Camera's frame numbers only increase (the recorder and the drop count rely
    // on it), and later gaps still count as drops.
    if (have_sequence_ && sequence < next_sequence_) {
      sequence_base_ += next_sequence_ - sequence;
      sequence = next_sequence_;
    }
    if (have_sequence_ && sequence > next_sequence_)
      counters_.dropped += sequence - next_sequence_;
    next_sequence_ = sequence + 1;
    have_sequence_ = true;

    if ((buf.flags & V4L2_BUF_FLAG_ERROR) != 0) {
      return Status::Error(StatusCode::kDataLoss, "camera %s: frame %llu marked corrupt by %s",
                           info_.name, static_cast<unsigned long long>(sequence), path_);
    }
    if (buf.bytesused < frame_bytes_) {
      return Status::Error(StatusCode::kDataLoss,
                           "camera %s: frame %llu has %u bytes, expected %zu", info_.name,
                           static_cast<unsigned long long>(sequence), buf.bytesused, frame_bytes_);
    }
    Frame frame;
    frame.sequence = sequence;
    if ((buf.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC) {
      frame.timestamp =
          Nanoseconds(static_cast<std::int64_t>(buf.timestamp.tv_sec) * 1'000'000'000 +
                      static_cast<std::int64_t>(buf.timestamp.tv_usec) * 1000);
    } else {
      frame.timestamp = now;  // the driver's clock is unknown: the dequeue time is ours
    }
    frame.image = dsp::ImageView{buffers_[buf.index].data(), info_.width, info_.height, stride_,
                                 info_.format};
    return frame;
  }
}

}  // namespace skyloc::drivers
