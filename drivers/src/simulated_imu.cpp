#include "skyloc/drivers/simulated_imu.h"

#include <cstdio>

namespace skyloc::drivers {

SimulatedImu::SimulatedImu(const SimulatedImuConfig& config,
                           std::span<const dsp::ImuSample> samples, const Clock* clock,
                           const ImuMounting& mounting)
    : ImuDevice(mounting, clock, config.recovery),
      config_(config),
      samples_(samples),
      clock_(clock) {
  std::snprintf(info_.name, sizeof(info_.name), "%s", config.name != nullptr ? config.name : "sim");
  info_.sample_rate_hz = config.sample_rate_hz;
  info_.has_gyro = config.has_gyro;
  std::snprintf(info_.source, sizeof(info_.source), "%zu simulated samples%s", samples.size(),
                clock != nullptr ? ", paced by the clock" : "");
}

Status SimulatedImu::InjectFault(const ImuFault& fault) {
  if (fault.kind != ImuFault::Kind::kVanish && fault.count == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "imu %s: a stall or drop needs count >= 1 (calls or samples it lasts)",
                         info_.name);
  }
  if (fault_count_ == faults_.size()) {
    return Status::Error(StatusCode::kResourceExhausted,
                         "imu %s: at most %zu faults can be scheduled", info_.name, faults_.size());
  }
  faults_[fault_count_++] = ScheduledFault{fault, false};
  return Status::Ok();
}

SimulatedImu::ScheduledFault* SimulatedImu::FaultAt(std::uint64_t index) {
  for (std::size_t i = 0; i < fault_count_; ++i) {
    if (!faults_[i].fired && faults_[i].fault.at_sample == index)
      return &faults_[i];
  }
  return nullptr;
}

Status SimulatedImu::DoOpen() {
  if (samples_.empty()) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "imu %s: no samples to replay (generate them from the trajectory first)",
                         info_.name);
  }
  for (std::size_t i = 1; i < samples_.size(); ++i) {
    if (samples_[i].timestamp_ns <= samples_[i - 1].timestamp_ns) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "imu %s: sample %zu's timestamp %lld ns is not after sample %zu's "
                           "(%lld ns); timestamps must strictly increase",
                           info_.name, i, static_cast<long long>(samples_[i].timestamp_ns), i - 1,
                           static_cast<long long>(samples_[i - 1].timestamp_ns));
    }
  }
  if (vanished_) {
    return Status::Error(StatusCode::kUnavailable,
                         "imu %s: device not present (simulated unplug at sample %llu)", info_.name,
                         static_cast<unsigned long long>(next_));
  }
  if (!resume_)
    next_ = 0;
  resume_ = false;
  for (std::size_t i = 0; i < fault_count_; ++i)
    faults_[i].fired = false;
  return Status::Ok();
}

Status SimulatedImu::DoStart() {
  stalls_left_ = 0;
  if (clock_ != nullptr && next_ < samples_.size()) {
    // The next sample is due now (or one sample interval after the last one delivered,
    // should the clock not have moved since), the rest at their own spacing.
    Nanoseconds due = clock_->Now();
    if (next_ > 0) {
      const Nanoseconds after_last = last_stamp_ + Nanoseconds(samples_[next_].timestamp_ns -
                                                               samples_[next_ - 1].timestamp_ns);
      if (due < after_last)
        due = after_last;
    }
    start_ = due - Nanoseconds(samples_[next_].timestamp_ns - samples_[0].timestamp_ns);
  }
  return Status::Ok();
}

Result<std::size_t> SimulatedImu::DoRead(std::span<dsp::ImuSample> out, Nanoseconds /*timeout*/) {
  std::size_t n = 0;
  while (n < out.size()) {
    if (vanished_)
      break;
    if (stalls_left_ > 0)
      break;
    if (next_ >= samples_.size())
      break;
    if (ScheduledFault* scheduled = FaultAt(next_); scheduled != nullptr) {
      scheduled->fired = true;
      switch (scheduled->fault.kind) {
        case ImuFault::Kind::kVanish:
          vanished_ = true;
          resume_ = true;
          continue;
        case ImuFault::Kind::kStall:
          stalls_left_ = scheduled->fault.count;
          continue;
        case ImuFault::Kind::kDrop: {
          const std::size_t left = samples_.size() - next_;
          const std::size_t drop = scheduled->fault.count < left ? scheduled->fault.count : left;
          next_ += drop;
          counters_.dropped += drop;
          continue;
        }
      }
    }
    dsp::ImuSample s = samples_[next_];
    if (clock_ != nullptr) {
      const Nanoseconds due = start_ + Nanoseconds(s.timestamp_ns - samples_[0].timestamp_ns);
      if (due > clock_->Now())
        break;
      s.timestamp_ns = due.count();
      last_stamp_ = due;
    }
    if (!config_.has_gyro)
      s.gyro_radps = {0, 0, 0};
    out[n++] = s;
    ++next_;
  }
  if (n > 0)
    return n;
  if (vanished_) {
    return Status::Error(StatusCode::kUnavailable,
                         "imu %s: device gone after %llu samples (simulated unplug)", info_.name,
                         static_cast<unsigned long long>(next_));
  }
  if (stalls_left_ > 0) {
    --stalls_left_;
    return Status::Error(StatusCode::kDeadlineExceeded,
                         "imu %s: no sample within the timeout (simulated stall)", info_.name);
  }
  if (next_ >= samples_.size()) {
    return Status::Error(StatusCode::kOutOfRange, "imu %s: end of the %zu simulated samples",
                         info_.name, samples_.size());
  }
  return Status::Error(StatusCode::kDeadlineExceeded,
                       "imu %s: no sample due yet within the timeout", info_.name);
}

void SimulatedImu::DoStop() {
  stalls_left_ = 0;
}

}  // namespace skyloc::drivers
