#include "skyloc/sim/rendered_source.h"

#include <cstdio>

namespace skyloc::sim {

RenderedSource::RenderedSource(const World* world, std::span<const TrajectoryPoint> trajectory,
                               const RenderedSourceConfig& config)
    : world_(world), trajectory_(trajectory), config_(config) {
  std::snprintf(name_, sizeof name_, "sim:%s:%s",
                world_ != nullptr ? WorldKindName(world_->kind) : "none",
                SpectrumName(config_.spectrum));
}

drivers::SimulatedCameraConfig RenderedSource::camera_config() const {
  drivers::SimulatedCameraConfig c;
  c.width = config_.lens.width;
  c.height = config_.lens.height;
  c.format =
      config_.spectrum == Spectrum::kUv ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24;
  // The trajectory's own spacing stamps the frames; this is only what pacing would use.
  if (trajectory_.size() >= 2 && trajectory_[1].time_s > trajectory_[0].time_s) {
    c.frame_interval = Nanoseconds(
        static_cast<std::int64_t>((trajectory_[1].time_s - trajectory_[0].time_s) * 1e9 + 0.5));
  }
  return c;
}

Status RenderedSource::Prepare(int width, int height, dsp::PixelFormat format) {
  const dsp::PixelFormat wanted =
      config_.spectrum == Spectrum::kUv ? dsp::PixelFormat::kGrey8 : dsp::PixelFormat::kRgb24;
  if (width != config_.lens.width || height != config_.lens.height || format != wanted) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "simulated camera: the lens renders %dx%d %s, the camera wants %dx%d %s",
                         config_.lens.width, config_.lens.height, dsp::PixelFormatName(wanted),
                         width, height, dsp::PixelFormatName(format));
  }
  if (world_ == nullptr)
    return Status::Error(StatusCode::kInvalidArgument, "simulated camera: no world");
  if (Status s = renderer_.Init(world_, config_.lens); !s.ok())
    return s.AddContext("simulated camera");
  return Status::Ok();
}

std::optional<Nanoseconds> RenderedSource::TimeOf(std::uint64_t index) const {
  if (index >= trajectory_.size())
    return std::nullopt;
  return Nanoseconds{
      static_cast<std::int64_t>(trajectory_[static_cast<std::size_t>(index)].time_s * 1e9 + 0.5)};
}

Status RenderedSource::Render(std::uint64_t index, dsp::MutableImageView out,
                              std::optional<drivers::Pose>* pose) {
  if (index >= trajectory_.size()) {
    return Status::Error(StatusCode::kOutOfRange,
                         "simulated camera: end of the trajectory (%zu frames)",
                         trajectory_.size());
  }
  const TrajectoryPoint& point = trajectory_[static_cast<std::size_t>(index)];
  SKYLOC_TRY(renderer_.Render(point.pose, config_.lighting, config_.spectrum, index, out));
  if (pose != nullptr)
    *pose = point.pose;
  return Status::Ok();
}

}  // namespace skyloc::sim
