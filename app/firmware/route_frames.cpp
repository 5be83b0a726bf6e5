// RouteFrames: a loaded route's frames in memory (route_db.h), allocated once at start-up.
#include <cstring>

#include "firmware/route_db.h"

namespace skyloc::firmware {

Status RouteFrames::Allocate(std::size_t capacity, std::size_t dim, std::size_t strip_columns,
                             RouteSink* sink) {
  sink_ = sink;
  const std::size_t kept = sink != nullptr ? 1 : capacity;
  SKYLOC_TRY(descriptors_.Allocate(kept * dim));
  SKYLOC_TRY(strips_.Allocate(kept * strip_columns));
  SKYLOC_TRY(meta_.Allocate(capacity));
  dim_ = dim;
  strip_columns_ = strip_columns;
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
    std::memcpy(slot.strip.data(), strip.data(), strip.size());
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
  if (size_ >= meta_.size() || (with_strip && strip_columns_ == 0))
    return {};
  if (size_ == 0)
    has_strips_ = with_strip;
  else if (with_strip != has_strips_)
    return {};
  meta_[size_] = meta;
  Slot slot;
  slot.descriptor = {descriptors_.data() + (sink_ != nullptr ? 0 : size_ * dim_), dim_};
  if (with_strip)
    slot.strip = {strips_.data() + (sink_ != nullptr ? 0 : size_ * strip_columns_), strip_columns_};
  ++size_;
  return slot;
}

}  // namespace skyloc::firmware
