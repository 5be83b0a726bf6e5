// libcamera 0.0.3 (Debian 12). API differences in later releases that matter here:
//  - generateConfiguration() takes `const StreamRoles&` (a std::vector) here; from 0.1 it
//    takes Span<const StreamRole>, so a braced list still compiles, a vector too.
//  - CameraConfiguration::orientation replaced `transform` in 0.2 (we leave both alone).
//  - Request::reuse(ReuseBuffers) and Signal::connect(obj, &T::member) are unchanged.
//  - formats::BGR888 is DRM naming: bytes R, G, B in memory (V4L2 RGB24); RGB888 is
//    B, G, R (V4L2 BGR24). Same in every version; easy to get backwards.
#include "skyloc/drivers/libcamera_camera.h"

#include <libcamera/libcamera.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>

namespace skyloc::drivers {
namespace {

struct LibcameraFormatChoice {
  libcamera::PixelFormat pixel_format;
  dsp::PixelFormat format;
};

// Greyscale first (monochrome UV sensors), then YUYV, then packed RGB.
const LibcameraFormatChoice kLibcameraFormats[] = {
    {libcamera::formats::R8, dsp::PixelFormat::kGrey8},
    {libcamera::formats::YUYV, dsp::PixelFormat::kYuyv},
    {libcamera::formats::BGR888, dsp::PixelFormat::kRgb24},
    {libcamera::formats::RGB888, dsp::PixelFormat::kBgr24},
};

// Set when a lost camera's CameraManager was let go of undestroyed (LibcameraCamera's
// header, Unplug): no other can be made in this process.
std::atomic<bool> g_manager_abandoned{false};

// libcamera returns -errno.
Status FromLibcamera(int ret, const char* camera, const char* what) {
  return Status::FromErrno(-ret, "camera %s: %s", camera, what);
}

}  // namespace

LibcameraCamera::LibcameraCamera(const LibcameraCameraConfig& config, const Clock* clock)
    : config_(config), clock_(clock != nullptr ? clock : &SystemMonotonicClock()) {
  config_.camera_id[sizeof(config_.camera_id) - 1] = '\0';
  std::snprintf(info_.name, sizeof(info_.name), "libcamera:%.53s",
                config_.camera_id[0] != '\0' ? config_.camera_id : "first");
  info_.width = config.capture.width;
  info_.height = config.capture.height;
}

LibcameraCamera::~LibcameraCamera() {
  Close();
}

Status LibcameraCamera::DoOpen() {
  // libcamera allows one CameraManager per process, and a lost camera's is never
  // destroyed (header, Unplug): a second one would abort inside libcamera.
  if (g_manager_abandoned.load(std::memory_order_acquire)) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "camera %s: a libcamera camera was lost earlier in this process; "
                         "restart skyloc to open a camera through libcamera again",
                         info_.name);
  }
  Status s = Configure();
  if (!s.ok())
    DoClose();
  return s;
}

Status LibcameraCamera::Configure() {
  if (config_.buffer_count < 1 || config_.buffer_count > kMaxRequests) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "camera %s: buffer_count %u is outside 1..%zu", info_.name,
                         config_.buffer_count, kMaxRequests);
  }
  const int efd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK | EFD_SEMAPHORE);
  if (efd < 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "camera %s: eventfd", info_.name);
  }
  completed_fd_.reset(efd);

  manager_ = std::make_unique<libcamera::CameraManager>();
  if (const int ret = manager_->start(); ret < 0)
    return FromLibcamera(ret, info_.name, "starting the camera manager");
  const bool first = config_.camera_id[0] == '\0' || std::strcmp(config_.camera_id, "first") == 0;
  if (first) {
    const auto cameras = manager_->cameras();
    if (!cameras.empty())
      camera_ = cameras.front();
  } else {
    camera_ = manager_->get(config_.camera_id);
  }
  if (!camera_) {
    return Status::Error(StatusCode::kNotFound,
                         "camera %s: libcamera found no such camera (list them with `cam -l`; "
                         "without udevd, libcamera needs /run/udev/data entries)",
                         info_.name);
  }
  if (const int ret = camera_->acquire(); ret < 0)
    return FromLibcamera(ret, info_.name, "acquire (another process uses the camera?)");
  acquired_ = true;

  const libcamera::StreamRole role =
      config_.raw ? libcamera::StreamRole::Raw : libcamera::StreamRole::Viewfinder;
  configuration_ = camera_->generateConfiguration({role});
  if (!configuration_ || configuration_->size() != 1) {
    return Status::Error(StatusCode::kUnimplemented, "camera %s: cannot make a %s stream",
                         info_.name, config_.raw ? "Raw" : "Viewfinder");
  }
  libcamera::StreamConfiguration& stream_config = configuration_->at(0);
  const LibcameraFormatChoice* choice = nullptr;
  for (const LibcameraFormatChoice& f : kLibcameraFormats) {
    for (const libcamera::PixelFormat& offered : stream_config.formats().pixelformats()) {
      if (offered == f.pixel_format && choice == nullptr)
        choice = &f;
    }
  }
  if (choice == nullptr) {
    return Status::Error(StatusCode::kUnimplemented,
                         "camera %s: none of R8, YUYV, BGR888, RGB888 offered for the %s stream "
                         "(see `cam -c <n> -I`)",
                         info_.name, config_.raw ? "Raw" : "Viewfinder");
  }
  stream_config.pixelFormat = choice->pixel_format;
  stream_config.size = libcamera::Size(static_cast<unsigned int>(config_.capture.width),
                                       static_cast<unsigned int>(config_.capture.height));
  stream_config.bufferCount = config_.buffer_count;
  if (configuration_->validate() == libcamera::CameraConfiguration::Invalid) {
    return Status::Error(
        StatusCode::kInvalidArgument, "camera %s: configuration %dx%d %s is invalid", info_.name,
        config_.capture.width, config_.capture.height, choice->pixel_format.toString().c_str());
  }
  if (stream_config.pixelFormat != choice->pixel_format) {
    return Status::Error(StatusCode::kUnimplemented, "camera %s: the pipeline changed %s to %s",
                         info_.name, choice->pixel_format.toString().c_str(),
                         stream_config.pixelFormat.toString().c_str());
  }
  if (const int ret = camera_->configure(configuration_.get()); ret < 0)
    return FromLibcamera(ret, info_.name, "configure");
  stream_ = stream_config.stream();
  info_.width = static_cast<int>(stream_config.size.width);
  info_.height = static_cast<int>(stream_config.size.height);
  info_.format = choice->format;
  const std::size_t row_bytes = static_cast<std::size_t>(info_.width) *
                                static_cast<std::size_t>(dsp::BytesPerPixelTimes2(info_.format)) /
                                2;
  stride_ = stream_config.stride >= row_bytes ? stream_config.stride : row_bytes;
  frame_bytes_ = stride_ * static_cast<std::size_t>(info_.height);

  allocator_ = std::make_unique<libcamera::FrameBufferAllocator>(camera_);
  if (const int ret = allocator_->allocate(stream_); ret < 0)
    return FromLibcamera(ret, info_.name, "allocating frame buffers");
  const auto& buffers = allocator_->buffers(stream_);
  request_count_ = buffers.size() < kMaxRequests ? buffers.size() : kMaxRequests;
  for (std::size_t i = 0; i < request_count_; ++i) {
    libcamera::FrameBuffer* buffer = buffers[i].get();
    if (buffer->planes().size() != 1) {
      return Status::Error(StatusCode::kUnimplemented,
                           "camera %s: buffer has %zu planes; skyloc reads packed formats only",
                           info_.name, buffer->planes().size());
    }
    const libcamera::FrameBuffer::Plane& plane = buffer->planes()[0];
    // Map from the start of the dmabuf once; the plane may start at an offset in it.
    if (Status s = mappings_[i].Map(plane.fd.get(), 0, plane.offset + plane.length); !s.ok())
      return s.AddContext("camera %s: buffer %zu", info_.name, i);
    plane_offsets_[i] = plane.offset;
    if (plane.length < frame_bytes_) {
      return Status::Error(StatusCode::kInternal,
                           "camera %s: buffer %zu has %u bytes, a frame needs %zu", info_.name, i,
                           plane.length, frame_bytes_);
    }
    requests_[i] = camera_->createRequest(i);
    if (!requests_[i])
      return Status::Error(StatusCode::kInternal, "camera %s: createRequest failed", info_.name);
    if (const int ret = requests_[i]->addBuffer(stream_, buffer); ret < 0)
      return FromLibcamera(ret, info_.name, "adding a buffer to a request");
  }
  camera_->requestCompleted.connect(this, &LibcameraCamera::OnRequestCompleted);
  camera_->disconnected.connect(this, &LibcameraCamera::OnDisconnected);
  disconnected_.store(false, std::memory_order_release);
  have_sequence_ = false;
  next_sequence_ = 0;
  return Status::Ok();
}

void LibcameraCamera::OnRequestCompleted(libcamera::Request* request) {
  // libcamera's thread: no allocation, no lock, no work. Hand over and wake the consumer.
  if (!completed_.TryPush(request)) {
    overflows_.fetch_add(1, std::memory_order_relaxed);
    return;
  }
  const std::uint64_t one = 1;
  (void)!::write(completed_fd_.get(), &one, sizeof(one));
}

void LibcameraCamera::OnDisconnected() {
  disconnected_.store(true, std::memory_order_release);
  const std::uint64_t one = 1;
  (void)!::write(completed_fd_.get(), &one, sizeof(one));
}

Status LibcameraCamera::QueueRequest(libcamera::Request* request) {
  // Never queue while stopping: libcamera 0.0.3 crashed when requests were queued during
  // stop() (seen in the VM study).
  if (stopping_.load(std::memory_order_acquire))
    return Status::Ok();
  if (const int ret = camera_->queueRequest(request); ret < 0)
    return FromLibcamera(ret, info_.name, "queueRequest");
  return Status::Ok();
}

Status LibcameraCamera::DoStart() {
  stopping_.store(false, std::memory_order_release);
  libcamera::ControlList controls(camera_->controls());
  const libcamera::ControlInfoMap& available = camera_->controls();
  fps_ = 0;
  if (config_.capture.fps > 0) {
    if (available.find(&libcamera::controls::FrameDurationLimits) != available.end()) {
      // The shortest and the longest frame duration both one frame at this rate: the
      // control's way to fix the rate (control_ids.h, FrameDurationLimits).
      const std::int64_t frame_us = std::llround(1e6 / config_.capture.fps);
      controls.set(libcamera::controls::FrameDurationLimits, {frame_us, frame_us});
      fps_ = config_.capture.fps;
    } else if (!told_rate_not_set_) {
      // Not an error: a camera without the control still streams, at its own rate. Said
      // once, on stderr, as the IIO IMU says its fallback to polling.
      std::fprintf(stderr,
                   "camera %s: fps %g not set: the camera has no FrameDurationLimits control, "
                   "so it runs at its own rate\n",
                   info_.name, config_.capture.fps);
      told_rate_not_set_ = true;
    }
  }
  if (config_.exposure_us > 0) {
    if (available.find(&libcamera::controls::ExposureTime) == available.end()) {
      return Status::Error(StatusCode::kUnimplemented,
                           "camera %s: exposure_us is set but the camera has no ExposureTime "
                           "control: remove exposure_us from the configuration",
                           info_.name);
    }
    if (available.find(&libcamera::controls::AeEnable) != available.end())
      controls.set(libcamera::controls::AeEnable, false);
    controls.set(libcamera::controls::ExposureTime, config_.exposure_us);
  }
  if (const int ret = camera_->start(&controls); ret < 0)
    return FromLibcamera(ret, info_.name, "start");
  started_ = true;
  last_progress_ = clock_->Now();
  held_ = nullptr;
  // libcamera numbers frames afresh after start(): continue our numbering.
  have_sequence_ = false;
  for (std::size_t i = 0; i < request_count_; ++i) {
    // After a Stop() the requests come back cancelled; libcamera asserts (and aborts) when
    // a request that is not pending is queued and completed again, so reset each one.
    requests_[i]->reuse(libcamera::Request::ReuseBuffers);
    Status s = QueueRequest(requests_[i].get());
    if (!s.ok()) {
      DoStop();
      return s;
    }
  }
  return Status::Ok();
}

Status LibcameraCamera::Lost(const char* why) {
  if (!lost_) {
    lost_ = true;
    std::snprintf(lost_why_, sizeof lost_why_, "%s", why);
  }
  return Status::Error(StatusCode::kFailedPrecondition,
                       "camera %s: lost (%s); libcamera cannot reopen it in this process: "
                       "skyloc exits and its service restarts it",
                       info_.name, lost_why_);
}

Result<Frame> LibcameraCamera::DoCapture(Nanoseconds timeout) {
  const Clock& clock = *clock_;
  if (lost_)
    return Lost(lost_why_);
  if (disconnected_.load(std::memory_order_acquire))
    return Lost("disconnected");
  if (held_ != nullptr) {
    held_->reuse(libcamera::Request::ReuseBuffers);
    libcamera::Request* request = held_;
    held_ = nullptr;
    SKYLOC_TRY(QueueRequest(request));
  }
  const Nanoseconds deadline = clock.Now() + timeout;
  libcamera::Request* request = nullptr;
  while (!completed_.TryPop(&request)) {
    if (disconnected_.load(std::memory_order_acquire))
      return Lost("disconnected");
    // Wait for a frame, but wake up in time to notice a stall.
    const Nanoseconds stall_at = last_progress_ + config_.stall_timeout;
    const Nanoseconds wake = deadline < stall_at ? deadline : stall_at;
    const Nanoseconds remaining = wake - clock.Now();
    const int timeout_ms = remaining <= Nanoseconds(0)
                               ? 0
                               : static_cast<int>((remaining.count() + 999'999) / 1'000'000);
    pollfd pfd{completed_fd_.get(), POLLIN, 0};
    const int ready = ::poll(&pfd, 1, timeout_ms);
    if (ready < 0) {
      const int saved = errno;
      if (saved == EINTR)
        continue;
      return Status::FromErrno(saved, "camera %s: poll", info_.name);
    }
    if (ready > 0) {
      std::uint64_t count = 0;
      (void)!::read(completed_fd_.get(), &count, sizeof(count));
      continue;
    }
    // poll() waited until `wake`: at `wake` at least (a ManualClock stands still).
    const Nanoseconds now = std::max(clock.Now(), wake);
    if (now >= stall_at) {
      char why[64];
      std::snprintf(why, sizeof why, "no frame for %lld ms",
                    static_cast<long long>(config_.stall_timeout.count() / 1'000'000));
      return Lost(why);
    }
    if (now >= deadline) {
      return Status::Error(StatusCode::kDeadlineExceeded, "camera %s: no frame within %lld ms",
                           info_.name, static_cast<long long>(timeout.count() / 1'000'000));
    }
  }
  held_ = request;  // requeued at the next Capture() or dropped by Stop()
  if (request->status() == libcamera::Request::RequestCancelled) {
    // The pipeline cancels what is in flight when the camera goes away.
    if (disconnected_.load(std::memory_order_acquire))
      return Lost("disconnected");
    return Status::Error(StatusCode::kUnavailable, "camera %s: request cancelled", info_.name);
  }
  last_progress_ = clock.Now();
  const libcamera::FrameBuffer* buffer = request->findBuffer(stream_);
  const std::size_t index = static_cast<std::size_t>(request->cookie());
  if (buffer == nullptr || index >= request_count_) {
    return Status::Error(StatusCode::kInternal, "camera %s: completed request has no buffer",
                         info_.name);
  }
  const libcamera::FrameMetadata& metadata = buffer->metadata();
  // Sequence numbers: libcamera's own restart at each start(); keep ours increasing.
  if (!have_sequence_) {
    sequence_base_ = next_sequence_ - metadata.sequence;
  }
  const std::uint64_t our_sequence = sequence_base_ + metadata.sequence;
  if (have_sequence_ && our_sequence > next_sequence_)
    counters_.dropped += our_sequence - next_sequence_;
  next_sequence_ = our_sequence + 1;
  have_sequence_ = true;
  if (metadata.status != libcamera::FrameMetadata::FrameSuccess) {
    return Status::Error(StatusCode::kDataLoss, "camera %s: frame %llu failed in the pipeline",
                         info_.name, static_cast<unsigned long long>(our_sequence));
  }
  const auto planes = metadata.planes();
  if (planes.size() < 1 || planes[0].bytesused < frame_bytes_) {
    return Status::Error(StatusCode::kDataLoss, "camera %s: frame %llu has %u bytes, expected %zu",
                         info_.name, static_cast<unsigned long long>(our_sequence),
                         planes.size() < 1 ? 0u : planes[0].bytesused, frame_bytes_);
  }
  Frame frame;
  frame.sequence = our_sequence;
  frame.timestamp = Nanoseconds(static_cast<std::int64_t>(metadata.timestamp));
  frame.image = dsp::ImageView{mappings_[index].data() + plane_offsets_[index], info_.width,
                               info_.height, stride_, info_.format};
  return frame;
}

void LibcameraCamera::DoStop() {
  if (!started_ || lost_)
    return;  // a lost camera is never stopped (header, Unplug)
  stopping_.store(true, std::memory_order_release);
  camera_->stop();  // completes (cancels) every pending request before returning
  started_ = false;
  held_ = nullptr;
  libcamera::Request* request = nullptr;
  while (completed_.TryPop(&request)) {
  }
  std::uint64_t count = 0;
  while (::read(completed_fd_.get(), &count, sizeof(count)) > 0) {
  }
}

void LibcameraCamera::DoClose() {
  if (lost_) {
    // Stopping, releasing or destroying what libcamera holds for a camera whose device is
    // gone aborts or crashes libcamera 0.0.3 (header, Unplug). Let go of it undestroyed:
    // our slots are disconnected so nothing calls back, the process is about to exit (or
    // would need a restart to use libcamera again anyway), and our own mappings go.
    if (camera_) {
      camera_->requestCompleted.disconnect(this);
      camera_->disconnected.disconnect(this);
    }
    (void)new std::shared_ptr<libcamera::Camera>(std::move(camera_));  // never freed
    (void)manager_.release();
    g_manager_abandoned.store(true, std::memory_order_release);
    (void)allocator_.release();
    (void)configuration_.release();
    for (auto& r : requests_)
      (void)r.release();
    for (MappedBuffer& m : mappings_)
      m.Unmap();
    request_count_ = 0;
    stream_ = nullptr;
    started_ = false;
    acquired_ = false;
    held_ = nullptr;
    completed_fd_.reset();
    return;
  }
  DoStop();
  if (camera_) {
    camera_->requestCompleted.disconnect(this);
    camera_->disconnected.disconnect(this);
  }
  for (auto& r : requests_)
    r.reset();
  for (MappedBuffer& m : mappings_)
    m.Unmap();
  request_count_ = 0;
  if (allocator_ && stream_ != nullptr)
    allocator_->free(stream_);
  allocator_.reset();
  stream_ = nullptr;
  configuration_.reset();
  if (camera_ && acquired_)
    camera_->release();
  acquired_ = false;
  camera_.reset();
  if (manager_)
    manager_->stop();
  manager_.reset();
  completed_fd_.reset();
}

}  // namespace skyloc::drivers
