// Attitude sources: the robot's roll and pitch at a frame's time, for the gravity-aligned
// sky descriptor (docs/ATTITUDE.md). One narrow interface, the shape of Camera (public
// non-virtual methods that check the call order once, private Do* hooks):
//
//   ImuAttitudeSource    an ImuDevice (the IIO driver, or its twin SimulatedImu fed by the
//                        simulator's IMU model) fused by dsp::AttitudeFilter, matched to the
//                        frame by timestamp: the estimate after every sample at or before
//                        the frame's time;
//   FrameAttitudeSource  the attitude that came with the frame (a dataset's roll_deg,
//                        pitch_deg columns).
//
// At() never blocks for long and allocates nothing. A source with nothing for a frame
// (none yet, or only samples older than the stale limit) returns kNotFound; a source
// that is gone (the IMU unplugged) returns kUnavailable until the IMU has reopened itself
// (ImuDevice, with the camera's backoff) and its samples reach the frames' time again.
// Either way the caller describes the frame as if level and counts it; it never drops the
// frame, and the gravity-aligned cap is back with the first frame that has an attitude.
#pragma once

#include <cstdint>
#include <span>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/imu_device.h"
#include "skyloc/dsp/attitude_filter.h"
#include "skyloc/dsp/imu.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

struct AttitudeCounters {
  std::uint64_t estimates = 0;    // At() calls answered with an attitude
  std::uint64_t missing = 0;      // At() calls answered kNotFound (none yet, or stale)
  std::uint64_t unavailable = 0;  // At() calls answered kUnavailable (the source is gone)
};

class AttitudeSource {
 public:
  virtual ~AttitudeSource() = default;
  AttitudeSource(const AttitudeSource&) = delete;
  AttitudeSource& operator=(const AttitudeSource&) = delete;

  // Start-up: finds and starts the device. An error names it and the fix.
  Status Open();
  // The attitude at `frame`'s time (kFailedPrecondition before Open()).
  Result<dsp::Attitude> At(const Frame& frame);
  void Close();

  bool is_open() const { return open_; }
  const char* name() const { return name_; }
  const AttitudeCounters& counters() const { return counters_; }

 protected:
  AttitudeSource() = default;
  char name_[96] = {};

 private:
  virtual Status DoOpen() = 0;
  virtual Result<dsp::Attitude> DoAt(const Frame& frame) = 0;
  virtual void DoClose() = 0;

  AttitudeCounters counters_;
  bool open_ = false;
};

// The attitude recorded with each frame (Frame::attitude): datasets.
class FrameAttitudeSource final : public AttitudeSource {
 public:
  explicit FrameAttitudeSource(const char* what = "the dataset's roll_deg,pitch_deg columns");

 private:
  Status DoOpen() override { return Status::Ok(); }
  Result<dsp::Attitude> DoAt(const Frame& frame) override;
  void DoClose() override {}
};

struct ImuAttitudeConfig {
  dsp::AttitudeFilterParams filter;
  // An estimate whose newest sample is older than this at the frame's time is stale.
  Nanoseconds stale{std::chrono::milliseconds(250)};
  std::size_t batch = 64;  // samples read from the device at a time (allocated at Open)
};

// An IMU through the attitude filter. The device must outlive the source; Open() opens and
// starts it (and Close() stops and closes it).
class ImuAttitudeSource final : public AttitudeSource {
 public:
  ImuAttitudeSource(ImuDevice* imu, const ImuAttitudeConfig& config);
  ~ImuAttitudeSource() override { Close(); }

  const dsp::AttitudeFilter& filter() const { return filter_; }

 private:
  Status DoOpen() override;
  Result<dsp::Attitude> DoAt(const Frame& frame) override;
  void DoClose() override;

  ImuDevice* imu_;
  ImuAttitudeConfig config_;
  dsp::AttitudeFilter filter_;
  FixedArray<dsp::ImuSample> batch_;
  std::size_t batch_size_ = 0;  // samples in batch_
  std::size_t batch_next_ = 0;  // the first not yet fed to the filter
  std::int64_t last_fed_ns_ = -1;
  bool ended_ = false;  // a finite source (the simulated IMU) has no more samples
};

}  // namespace skyloc::drivers
