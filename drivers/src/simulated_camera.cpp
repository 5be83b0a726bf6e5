#include "skyloc/drivers/simulated_camera.h"

#include <cstdio>
#include <thread>

namespace skyloc::drivers {

SimulatedCamera::SimulatedCamera(const SimulatedCameraConfig& config, FrameSource* source,
                                 const Clock* clock)
    : config_(config), source_(source), clock_(clock) {
  const char* name = config.name;
  if (name == nullptr)
    name = source != nullptr ? source->name() : "sim";
  std::snprintf(info_.name, sizeof(info_.name), "%s", name);
  info_.width = config.width;
  info_.height = config.height;
  info_.format = config.format;
}

Status SimulatedCamera::InjectFault(const CameraFault& fault) {
  if (fault.count == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "camera %s: a fault needs count >= 1 (frames or calls it lasts)",
                         info_.name);
  }
  if (fault_count_ == faults_.size()) {
    return Status::Error(StatusCode::kResourceExhausted,
                         "camera %s: at most %zu faults can be scheduled", info_.name,
                         faults_.size());
  }
  faults_[fault_count_++] = ScheduledFault{fault, false};
  return Status::Ok();
}

SimulatedCamera::ScheduledFault* SimulatedCamera::FaultAt(std::uint64_t index) {
  for (std::size_t i = 0; i < fault_count_; ++i) {
    if (!faults_[i].fired && faults_[i].fault.at_frame == index)
      return &faults_[i];
  }
  return nullptr;
}

Status SimulatedCamera::DoOpen() {
  if (source_ == nullptr || clock_ == nullptr) {
    return Status::Error(StatusCode::kInvalidArgument, "camera %s: no frame source or clock given",
                         info_.name);
  }
  if (config_.width <= 0 || config_.height <= 0 ||
      (config_.format == dsp::PixelFormat::kYuyv && config_.width % 2 != 0)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "camera %s: invalid frame size %dx%d for %s (YUYV needs an even width)",
                         info_.name, config_.width, config_.height,
                         dsp::PixelFormatName(config_.format));
  }
  stride_ = static_cast<std::size_t>(config_.width) *
            static_cast<std::size_t>(dsp::BytesPerPixelTimes2(config_.format)) / 2;
  // Not SKYLOC_TRY(x.AddContext(...)): AddContext returns a reference into the temporary,
  // which the macro would keep past its lifetime.
  if (Status s = pixels_.Allocate(stride_ * static_cast<std::size_t>(config_.height)); !s.ok())
    return s.AddContext("camera %s: frame buffer", info_.name);
  if (Status s = source_->Prepare(config_.width, config_.height, config_.format); !s.ok())
    return s.AddContext("camera %s", info_.name);
  frame_count_ = config_.frame_count;
  const std::uint64_t source_frames = source_->frame_count();
  if (source_frames != 0 && (frame_count_ == 0 || source_frames < frame_count_))
    frame_count_ = source_frames;
  next_index_ = 0;
  have_timestamp_ = false;
  for (std::size_t i = 0; i < fault_count_; ++i)
    faults_[i].fired = false;
  return Status::Ok();
}

Status SimulatedCamera::DoStart() {
  start_index_ = next_index_;
  start_time_ = clock_->Now();
  stalls_left_ = 0;
  unplugged_left_ = 0;
  reconnect_pending_ = false;
  return Status::Ok();
}

Result<Frame> SimulatedCamera::DoCapture(Nanoseconds /*timeout*/) {
  for (;;) {
    if (unplugged_left_ > 0) {
      --unplugged_left_;
      reconnect_pending_ = true;
      return Status::Error(StatusCode::kUnavailable,
                           "camera %s: device disconnected (simulated); reopening", info_.name);
    }
    if (reconnect_pending_) {
      reconnect_pending_ = false;
      ++counters_.restarts;
    }
    if (stalls_left_ > 0) {
      --stalls_left_;
      return Status::Error(StatusCode::kDeadlineExceeded,
                           "camera %s: no frame within the timeout (simulated stall)", info_.name);
    }
    if (frame_count_ != 0 && next_index_ >= frame_count_) {
      return Status::Error(StatusCode::kOutOfRange, "camera %s: end of source after %llu frames",
                           info_.name, static_cast<unsigned long long>(frame_count_));
    }
    ScheduledFault* scheduled = FaultAt(next_index_);
    if (scheduled == nullptr)
      break;
    scheduled->fired = true;
    const CameraFault& fault = scheduled->fault;
    switch (fault.kind) {
      case CameraFault::Kind::kDrop:
        next_index_ += fault.count;
        counters_.dropped += fault.count;
        break;
      case CameraFault::Kind::kStall:
        stalls_left_ = fault.count;
        break;
      case CameraFault::Kind::kDisconnect:
        unplugged_left_ = fault.count;
        break;
      case CameraFault::Kind::kCorruptSize: {
        const std::uint64_t lost = next_index_++;
        return Status::Error(StatusCode::kDataLoss,
                             "camera %s: frame %llu has %zu bytes, expected %zu (simulated "
                             "corrupt frame)",
                             info_.name, static_cast<unsigned long long>(lost), pixels_.size() / 2,
                             pixels_.size());
      }
    }
  }

  const dsp::MutableImageView out{pixels_.data(), config_.width, config_.height, stride_,
                                  config_.format};
  Frame frame;
  const std::uint64_t index = next_index_++;
  frame.sequence = index;
  if (Status s = source_->Render(index, out, &frame.pose); !s.ok())
    return s.AddContext("camera %s: frame %llu", info_.name,
                        static_cast<unsigned long long>(index));
  if (config_.paced) {
    const Nanoseconds due =
        start_time_ + config_.frame_interval * static_cast<std::int64_t>(index - start_index_);
    const Nanoseconds now = clock_->Now();
    if (now < due)
      std::this_thread::sleep_for(due - now);
  }
  Nanoseconds stamp = clock_->Now();
  if (const std::optional<Nanoseconds> at = source_->TimeOf(index)) {
    stamp = *at;
  } else if (have_timestamp_ && stamp < last_timestamp_ + config_.frame_interval) {
    stamp = last_timestamp_ + config_.frame_interval;
  }
  last_timestamp_ = stamp;
  have_timestamp_ = true;
  frame.timestamp = stamp;
  frame.image = out;
  return frame;
}

void SimulatedCamera::DoStop() {
  stalls_left_ = 0;
  unplugged_left_ = 0;
  reconnect_pending_ = false;
}

void SimulatedCamera::DoClose() {}

}  // namespace skyloc::drivers
