// The IMU's simulated twin: replays samples given at start-up (the simulator generates them
// from a trajectory; tests write closed forms), optionally paced by an injected Clock, with
// scripted faults reported through the same Status codes and ImuCounters as the IIO driver:
//
//   fault      what Read() does                                             counters
//   kVanish    delivers samples up to `at_sample`, then the device is gone:    errors,
//              Read() returns kUnavailable and Open() fails (so ImuDevice's     outages
//              reopens fail and back off, as the IIO driver's do) until
//              ClearFaults() plugs it back; it then resumes at `at_sample`
//   kStall     `count` calls return kDeadlineExceeded, then samples resume     errors
//   kDrop      samples `at_sample .. at_sample+count-1` are skipped            dropped += count
//
// Stalls and drops fire once per Open(). Open() replays from the first sample, except
// after a vanish (a replugged device goes on from where it was). Read() never blocks (like
// SimulatedCamera): with no sample due it returns kDeadlineExceeded at once, so tests of
// timing take no wall time.
//
// Pacing: without a clock every remaining sample is available at once, with the samples'
// own timestamps. With a clock, sample i is due at t0 + (ts_i - ts_0), where t0 is the
// clock's time at Start(), and is stamped with that time, so the IMU and a SimulatedCamera
// on the same clock share one time base.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "skyloc/drivers/imu_device.h"
#include "skyloc/dsp/imu.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

struct ImuFault {
  enum class Kind : std::uint8_t { kVanish, kStall, kDrop };
  Kind kind = Kind::kVanish;
  std::uint64_t at_sample = 0;  // index into the samples at which the fault strikes
  std::uint32_t count = 1;      // calls stalled, or samples dropped (kVanish: unused)
};

struct SimulatedImuConfig {
  const char* name = "sim:imu";
  double sample_rate_hz = 200.0;  // reported in info(); the samples' timestamps set the pace
  bool has_gyro = true;
  // Reopening after a vanish, timed by the clock.
  StreamRecoveryConfig recovery = ImuRecoveryConfig();
};

class SimulatedImu final : public ImuDevice {
 public:
  static constexpr std::size_t kMaxFaults = 16;

  // `samples` (timestamps strictly increasing; IMU frame) and `clock` (nullptr: unpaced,
  // and reopens timed by SystemMonotonicClock()) must outlive the device. Nothing here can
  // fail: Open() checks the samples.
  SimulatedImu(const SimulatedImuConfig& config, std::span<const dsp::ImuSample> samples,
               const Clock* clock = nullptr, const ImuMounting& mounting = {});
  ~SimulatedImu() override { Close(); }

  // Schedules a fault. kResourceExhausted once kMaxFaults are scheduled.
  Status InjectFault(const ImuFault& fault);
  // Removes every fault; a vanished device is plugged back (its next Open() succeeds).
  void ClearFaults() {
    fault_count_ = 0;
    vanished_ = false;
  }

 private:
  Status DoOpen() override;
  Status DoStart() override;
  Result<std::size_t> DoRead(std::span<dsp::ImuSample> out, Nanoseconds timeout) override;
  void DoStop() override;
  void DoClose() override {}

  struct ScheduledFault {
    ImuFault fault;
    bool fired = false;
  };
  ScheduledFault* FaultAt(std::uint64_t index);

  SimulatedImuConfig config_;
  std::span<const dsp::ImuSample> samples_;
  const Clock* clock_;
  std::array<ScheduledFault, kMaxFaults> faults_{};
  std::size_t fault_count_ = 0;

  std::size_t next_ = 0;  // next sample to deliver
  std::uint32_t stalls_left_ = 0;
  bool vanished_ = false;      // gone until ClearFaults()
  bool resume_ = false;        // the next Open() goes on from next_ (after a vanish)
  Nanoseconds start_{0};       // when samples_[0] would have been due (paced)
  Nanoseconds last_stamp_{0};  // of the last sample delivered (paced)
};

}  // namespace skyloc::drivers
