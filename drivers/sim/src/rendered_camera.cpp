#include "skyloc/sim/rendered_camera.h"

#include <cstdio>

namespace skyloc::sim {

RenderedCamera::RenderedCamera(const World* world, std::span<const TrajectoryPoint> trajectory,
                               const RenderedCameraConfig& config)
    : world_(world), trajectory_(trajectory), config_(config) {}

Status RenderedCamera::DoOpen() {
  if (Status s = renderer_.Init(world_, config_.lens); !s.ok())
    return s.AddContext("simulated camera");
  const bool uv = config_.spectrum == Spectrum::kUv;
  const auto bytes = static_cast<std::size_t>(config_.lens.width) *
                     static_cast<std::size_t>(config_.lens.height) * (uv ? 1u : 3u);
  SKYLOC_TRY(buffer_.Allocate(bytes));
  std::snprintf(info_.name, sizeof info_.name, "sim:%s:%s", WorldKindName(world_->kind),
                SpectrumName(config_.spectrum));
  info_.width = config_.lens.width;
  info_.height = config_.lens.height;
  info_.format = uv ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24;
  return Status::Ok();
}

Status RenderedCamera::DoStart() {
  next_ = 0;
  return Status::Ok();
}

Result<drivers::Frame> RenderedCamera::DoCapture(Nanoseconds /*timeout*/) {
  if (next_ >= trajectory_.size()) {
    return Status::Error(StatusCode::kOutOfRange,
                         "simulated camera: end of the trajectory (%zu frames)",
                         trajectory_.size());
  }
  const TrajectoryPoint& point = trajectory_[next_];
  const dsp::MutableImageView view{
      buffer_.data(), info_.width, info_.height,
      static_cast<std::size_t>(info_.width) * (info_.format == dsp::PixelFormat::kGrey8 ? 1u : 3u),
      info_.format};
  const Status rendered =
      renderer_.Render(point.pose, config_.lighting, config_.spectrum, next_, view);
  if (!rendered.ok())
    return rendered;
  drivers::Frame frame;
  frame.image = view;
  frame.sequence = next_;
  frame.timestamp = Nanoseconds{static_cast<std::int64_t>(point.time_s * 1e9 + 0.5)};
  frame.pose = point.pose;
  ++next_;
  return frame;
}

}  // namespace skyloc::sim
