#include "firmware/output_publisher.h"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>

namespace skyloc::firmware {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

// Snprintf's count, or what is left of `size` (an overlong line is cut, and then not sent).
std::size_t Used(int n, std::size_t size) {
  return n < 0 ? size : static_cast<std::size_t>(n);
}

}  // namespace

std::size_t FormatJsonLine(LoopMode mode, const FrameResult& r, std::uint64_t route_frames,
                           double distance_m, char* out, std::size_t size) {
  const double t = static_cast<double>(r.timestamp.count()) * 1e-9;
  const long long latency_us = static_cast<long long>(r.latency.count() / 1000);
  const auto frame = static_cast<unsigned long long>(r.frame);
  int n;
  if (mode == LoopMode::kRecord || mode == LoopMode::kWaitForButton) {
    n = std::snprintf(out, size,
                      "{\"schema\":%d,\"frame\":%llu,\"timestamp\":%.6f,\"latency_us\":%lld}\n",
                      drivers::kLocalisationSchema, frame, t, latency_us);
  } else if (mode == LoopMode::kTeach) {
    n = std::snprintf(out, size,
                      "{\"schema\":%d,\"frame\":%llu,\"timestamp\":%.6f,\"route_frames\":%llu,"
                      "\"threshold\":%d,\"sky_fraction\":%.4f,\"latency_us\":%lld}\n",
                      drivers::kLocalisationSchema, frame, t,
                      static_cast<unsigned long long>(route_frames), r.threshold,
                      static_cast<double>(r.sky_fraction), latency_us);
  } else {
    char index[24] = "null", distance[32] = "null";
    if (r.matched) {
      std::snprintf(index, sizeof index, "%lld", static_cast<long long>(r.best_index));
      if (std::isfinite(distance_m))
        std::snprintf(distance, sizeof distance, "%.2f", distance_m);
    }
    // null when there is no estimate (no match, a route without strips, no RANSAC model).
    char heading[24] = "null", heading_confidence[24] = "null", surf[24] = "null";
    if (r.has_heading) {
      std::snprintf(heading, sizeof heading, "%.2f", static_cast<double>(r.heading_deg));
      std::snprintf(heading_confidence, sizeof heading_confidence, "%.4f",
                    static_cast<double>(r.heading_confidence));
    }
    if (r.has_heading_surf)
      std::snprintf(surf, sizeof surf, "%.2f", static_cast<double>(r.heading_surf_deg));
    n = std::snprintf(out, size,
                      "{\"schema\":%d,\"frame\":%llu,\"timestamp\":%.6f,\"best_index\":%s,"
                      "\"route_length\":%llu,\"distance_m\":%s,\"uniqueness\":%.4f,"
                      "\"confidence\":%.4f,\"state\":\"%s\",\"heading_deg\":%s,"
                      "\"heading_confidence\":%s,\"heading_surf_deg\":%s,"
                      "\"heading_surf_inliers\":%d,\"latency_us\":%lld}\n",
                      drivers::kLocalisationSchema, frame, t, index,
                      static_cast<unsigned long long>(route_frames), distance,
                      static_cast<double>(r.uniqueness), static_cast<double>(r.confidence),
                      dsp::LocalisationStateName(r.state), heading, heading_confidence, surf,
                      r.has_heading_surf ? r.heading_surf_inliers : 0, latency_us);
  }
  const std::size_t used = Used(n, size);
  return used < size ? used : 0;
}

void BuildLocalisationMessage(LoopMode mode, const FrameResult& r, std::uint64_t route_frames,
                              double distance_m, drivers::LocalisationMessage* m) {
  const bool repeat = mode == LoopMode::kRepeat;
  m->frame = r.frame;
  m->timestamp_ns = r.timestamp.count();
  m->state = static_cast<std::uint8_t>(r.state);
  m->localising = repeat;
  m->confidence = r.confidence;
  m->uniqueness = r.uniqueness;
  m->route_index = repeat && r.matched ? r.best_index : -1;
  m->route_length = route_frames;
  m->distance_along_m = repeat && r.matched ? distance_m : kNaN;
  const float no_heading = std::numeric_limits<float>::quiet_NaN();
  m->heading_deg = repeat && r.has_heading ? r.heading_deg : no_heading;
  m->heading_confidence = repeat && r.has_heading ? r.heading_confidence : no_heading;
  m->latency_us = static_cast<std::uint32_t>(r.latency.count() / 1000);
  m->json_length = static_cast<std::uint32_t>(
      FormatJsonLine(mode, r, route_frames, distance_m, m->json, sizeof m->json));
  m->devices_length = 0;
}

void RouteProgress::Follow(const RouteFrames* route) {
  const std::size_t n = route == nullptr ? 0 : route->size();
  if (n == length_)
    return;
  length_ = n < along_m_.size() ? n : along_m_.size();
  double along = 0;
  for (std::size_t i = 0; i < length_; ++i) {
    const std::optional<drivers::Pose>& pose = route->meta(i).pose;
    const std::optional<drivers::Pose>& before = route->meta(i == 0 ? 0 : i - 1).pose;
    if (!pose || !before)
      along = kNaN;
    else if (i > 0)
      along += std::hypot(pose->x_m - before->x_m, pose->y_m - before->y_m);
    along_m_[i] = along;
  }
}

double RouteProgress::DistanceTo(std::int64_t index) const {
  if (index < 0 || static_cast<std::uint64_t>(index) >= length_)
    return kNaN;
  return along_m_[static_cast<std::size_t>(index)];
}

OutputPublisher::~OutputPublisher() {
  Stop();
}

Status OutputPublisher::Start(std::span<drivers::LocalisationOutput* const> outputs,
                              const RouteFrames* route, std::size_t route_capacity,
                              PublishMode mode) {
  if (running())
    return Status::Error(StatusCode::kFailedPrecondition, "the output publisher is running");
  outputs_ = outputs;
  route_ = route;
  mode_ = mode;
  SKYLOC_TRY(progress_.Allocate(route_capacity));
  queue_ = std::make_unique<Queue>();
  building_ = std::make_unique<drivers::LocalisationMessage>();
  popped_ = std::make_unique<drivers::LocalisationMessage>();
  running_ = true;
  thread_ = std::thread([this] { PublishLoop(); });
  return Status::Ok();
}

void OutputPublisher::OnFrame(LoopMode mode, const FrameResult& r, std::uint64_t route_frames) {
  if (!running())
    return;
  frames_.fetch_add(1, std::memory_order_relaxed);
  last_state_.store(static_cast<std::uint8_t>(r.state), std::memory_order_relaxed);
  double distance = kNaN;
  if (mode == LoopMode::kRepeat) {
    progress_.Follow(route_);
    route_frames = progress_.length();
    distance = progress_.DistanceTo(r.matched ? r.best_index : -1);
  }
  BuildLocalisationMessage(mode, r, route_frames, distance, building_.get());
  if (devices_ != nullptr && r.timestamp >= devices_due_) {
    drivers::LocalisationMessage& m = *building_;
    m.devices_length = static_cast<std::uint32_t>(
        devices_->FormatJson(static_cast<double>(r.timestamp.count()) * 1e-9,
                             m.json + m.json_length, sizeof m.json - m.json_length));
    devices_due_ = r.timestamp + std::chrono::seconds(1);
  }
  while (!queue_->TryPush(*building_)) {
    if (mode_ == PublishMode::kDropWhenFull) {
      queue_dropped_.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    std::this_thread::yield();
  }
  queued_.release();
}

void OutputPublisher::PublishLoop() {
  // Off the frame loop, one message at a time in frame order; the health once a second.
  auto next_health = std::chrono::steady_clock::now() + std::chrono::seconds(1);
  drivers::LocalisationMessage& message = *popped_;
  for (;;) {
    const bool woken = queued_.try_acquire_until(next_health);
    if (woken) {
      if (!queue_->TryPop(&message))
        return;  // Stop()'s release: everything before it has been published
      for (drivers::LocalisationOutput* output : outputs_)
        output->Publish(message);
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= next_health) {
      next_health = now + std::chrono::seconds(1);
      char text[256];
      const OutputPublisherCounters c = counters();
      std::snprintf(text, sizeof text, "frames=%llu\nqueue_dropped=%llu\nstate=%s\n",
                    static_cast<unsigned long long>(c.frames),
                    static_cast<unsigned long long>(c.queue_dropped),
                    dsp::LocalisationStateName(static_cast<dsp::LocalisationState>(
                        last_state_.load(std::memory_order_relaxed))));
      for (drivers::LocalisationOutput* output : outputs_)
        output->PublishHealth(text);
    }
  }
}

void OutputPublisher::Stop() {
  if (!running_)
    return;
  running_ = false;
  if (!thread_.joinable())
    return;
  queued_.release();
  thread_.join();
}

OutputPublisherCounters OutputPublisher::counters() const {
  return {frames_.load(std::memory_order_relaxed), queue_dropped_.load(std::memory_order_relaxed)};
}

}  // namespace skyloc::firmware
