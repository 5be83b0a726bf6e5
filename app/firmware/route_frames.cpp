// RouteFrames: a loaded route's frames in memory (route_db.h), allocated once at start-up.
#include <cmath>
#include <cstring>
#include <limits>

#include "firmware/route_db.h"

namespace skyloc::firmware {

drivers::Pose RoutePoseFloats(const drivers::Pose& p) {
  const auto f = [](double v) { return static_cast<double>(static_cast<float>(v)); };
  return drivers::Pose{f(p.x_m), f(p.y_m), f(p.z_m), f(p.roll_deg), f(p.pitch_deg), f(p.yaw_deg)};
}

RouteFrameMeta RouteFrames::meta(std::size_t i) const {
  RouteFrameMeta m;
  m.timestamp_ns = timestamps_[i];
  const std::array<float, 6>& p = poses_[i];
  if (!std::isnan(p[0])) {
    const auto d = [](float v) { return static_cast<double>(v); };
    m.pose = drivers::Pose{d(p[0]), d(p[1]), d(p[2]), d(p[3]), d(p[4]), d(p[5])};
  }
  return m;
}

Status RouteFrames::Allocate(std::size_t capacity, std::size_t dim, std::size_t strip_columns,
                             RouteSink* sink) {
  sink_ = sink;
  const std::size_t kept = sink != nullptr ? 1 : capacity;
  const std::size_t strip_bytes = strip_columns != 0 ? dsp::PackedStripBytes(strip_columns) : 0;
  SKYLOC_TRY(descriptors_.Allocate(kept * dim));
  SKYLOC_TRY(strips_.Allocate(kept * strip_bytes));
  SKYLOC_TRY(timestamps_.Allocate(capacity));
  SKYLOC_TRY(poses_.Allocate(capacity));
  dim_ = dim;
  strip_columns_ = strip_columns;
  strip_bytes_ = strip_bytes;
  Clear();
  return Status::Ok();
}

bool RouteFrames::Append(const RouteFrameMeta& meta, std::span<const float> descriptor,
                         std::span<const std::uint8_t> strip) {
  if (descriptor.size() != dim_ || (!strip.empty() && strip.size() != strip_columns_))
    return false;
  const Slot slot = Emplace(meta, !strip.empty());
  if (slot.descriptor.empty())
    return false;
  std::memcpy(slot.descriptor.data(), descriptor.data(), slot.descriptor.size_bytes());
  if (!strip.empty())
    (void)dsp::PackStrip(strip, slot.strip);  // the lengths were checked above
  if (!Complete(slot).ok()) {
    --size_;  // the sink refused it (full): the frame is not part of the route
    return false;
  }
  return true;
}

Status RouteFrames::Complete(const Slot& slot) {
  if (sink_ == nullptr)
    return Status::Ok();
  return sink_->AddFrame(slot.descriptor, slot.strip);
}

RouteFrames::Slot RouteFrames::Emplace(const RouteFrameMeta& meta, bool with_strip) {
  if (size_ >= timestamps_.size() || (with_strip && strip_columns_ == 0))
    return {};
  if (size_ == 0)
    has_strips_ = with_strip;
  else if (with_strip != has_strips_)
    return {};
  timestamps_[size_] = meta.timestamp_ns;
  std::array<float, 6>& pose = poses_[size_];
  if (meta.pose) {
    pose = {static_cast<float>(meta.pose->x_m),       static_cast<float>(meta.pose->y_m),
            static_cast<float>(meta.pose->z_m),       static_cast<float>(meta.pose->roll_deg),
            static_cast<float>(meta.pose->pitch_deg), static_cast<float>(meta.pose->yaw_deg)};
  } else {
    pose.fill(std::numeric_limits<float>::quiet_NaN());
  }
  Slot slot;
  slot.descriptor = {descriptors_.data() + (sink_ != nullptr ? 0 : size_ * dim_), dim_};
  if (with_strip)
    slot.strip = {strips_.data() + (sink_ != nullptr ? 0 : size_ * strip_bytes_), strip_bytes_};
  ++size_;
  return slot;
}

}  // namespace skyloc::firmware
