#include "skyloc/drivers/attitude_source.h"

#include <cstdio>

#include "skyloc/drivers/dsp_status.h"

namespace skyloc::drivers {

Status AttitudeSource::Open() {
  if (open_)
    return Status::Error(StatusCode::kFailedPrecondition, "attitude source %s is already open",
                         name_);
  SKYLOC_TRY(DoOpen());
  open_ = true;
  return Status::Ok();
}

Result<dsp::Attitude> AttitudeSource::At(const Frame& frame) {
  if (!open_)
    return Status::Error(StatusCode::kFailedPrecondition, "attitude source %s: At() before Open()",
                         name_);
  Result<dsp::Attitude> a = DoAt(frame);
  if (a.ok())
    ++counters_.estimates;
  else if (a.status().code() == StatusCode::kUnavailable)
    ++counters_.unavailable;
  else
    ++counters_.missing;
  return a;
}

void AttitudeSource::Close() {
  if (!open_)
    return;
  DoClose();
  open_ = false;
}

// ---------------------------------------------------------------------------------------

FrameAttitudeSource::FrameAttitudeSource(const char* what) {
  std::snprintf(name_, sizeof name_, "%s", what);
}

Result<dsp::Attitude> FrameAttitudeSource::DoAt(const Frame& frame) {
  if (!frame.attitude)
    return Status::Error(StatusCode::kNotFound, "frame %llu has no recorded attitude",
                         static_cast<unsigned long long>(frame.sequence));
  return *frame.attitude;
}

// ---------------------------------------------------------------------------------------

ImuAttitudeSource::ImuAttitudeSource(ImuDevice* imu, const ImuAttitudeConfig& config)
    : imu_(imu), config_(config) {
  std::snprintf(name_, sizeof name_, "imu");
}

Status ImuAttitudeSource::DoOpen() {
  if (imu_ == nullptr)
    return Status::Error(StatusCode::kInvalidArgument, "attitude source: no IMU");
  if (const dsp::AttitudeError e = filter_.Init(config_.filter); e != dsp::AttitudeError::kOk)
    return DspStatus(e, "[attitude] filter");
  SKYLOC_TRY(batch_.Allocate(config_.batch < 1 ? 1 : config_.batch));
  batch_size_ = batch_next_ = 0;
  last_fed_ns_ = -1;
  ended_ = false;
  SKYLOC_TRY(imu_->Open());
  if (Status s = imu_->Start(); !s.ok()) {
    imu_->Close();
    return s;
  }
  std::snprintf(name_, sizeof name_, "%s", imu_->info().name);
  return Status::Ok();
}

Result<dsp::Attitude> ImuAttitudeSource::DoAt(const Frame& frame) {
  const std::int64_t t = frame.timestamp.count();
  // Feed every sample at or before the frame's time; a later one waits in the batch for
  // the next frame. Reads never wait: the samples up to a captured frame's time are in.
  while (true) {
    if (batch_next_ == batch_size_) {
      if (ended_)
        break;
      Result<std::size_t> n = imu_->Read(batch_.span(), Nanoseconds{0});
      if (!n.ok()) {
        const StatusCode code = n.status().code();
        if (code == StatusCode::kDeadlineExceeded)
          break;  // nothing new yet
        if (code == StatusCode::kOutOfRange) {
          ended_ = true;  // a finite source ran out: its last estimate goes stale
          break;
        }
        // Gone (kUnavailable): the device reopens itself (ImuDevice) and later frames
        // read again; the filter restarts from the first sample after the gap. The
        // device's message already names it.
        const bool gone = code == StatusCode::kUnavailable;
        return Status::Error(gone ? StatusCode::kUnavailable : StatusCode::kNotFound, "%s",
                             n.status().message());
      }
      batch_size_ = *n;
      batch_next_ = 0;
      continue;
    }
    const dsp::ImuSample& sample = batch_[batch_next_];
    if (sample.timestamp_ns > t)
      break;
    ++batch_next_;
    // A sample the filter refuses (a repeated timestamp, NaN) is skipped; the filter
    // restarts itself after a gap.
    if (filter_.Update(sample) == dsp::AttitudeError::kOk)
      last_fed_ns_ = sample.timestamp_ns;
  }
  if (!filter_.has_estimate() || last_fed_ns_ < 0)
    return Status::Error(StatusCode::kNotFound, "IMU %s: no sample before frame %llu yet", name_,
                         static_cast<unsigned long long>(frame.sequence));
  if (t - last_fed_ns_ > config_.stale.count())
    return Status::Error(StatusCode::kNotFound,
                         "IMU %s: newest sample %.3f s before frame %llu (stale)", name_,
                         static_cast<double>(t - last_fed_ns_) * 1e-9,
                         static_cast<unsigned long long>(frame.sequence));
  dsp::Attitude a = filter_.attitude();
  a.timestamp_ns = last_fed_ns_;
  return a;
}

void ImuAttitudeSource::DoClose() {
  imu_->Stop();
  imu_->Close();
}

}  // namespace skyloc::drivers
