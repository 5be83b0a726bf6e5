// The interface every attitude source's IMU implements: the Linux IIO driver, the
// simulated IMU. The same shape as Camera: public non-virtual methods check the call order
// once, here, and apply the mounting rotation, so every implementation behaves the same
// way to the attitude filter; implementations override the private Do* hooks only.
//
//   Closed --Open()--> Open --Start()--> Streaming --Stop()--> Open --Close()--> Closed
//
// Buffers are allocated in Open()/Start(); Read() allocates nothing.
//
// Healing: when a Read() finds the device gone (kUnavailable: unplugged, driver unbound,
// the simulated twin's kVanish), the device is closed and an outage counted; later Read()
// calls reopen it (DoOpen, DoStart) with the V4L2 camera's backoff (StreamRecovery:
// 100 ms, doubling, on the device's Clock), capped at 500 ms (ImuRecoveryConfig) where the
// camera's is 2 s, and return kUnavailable until a reopen succeeds, which counts a reopen;
// samples then flow again with no call from the caller. Read() does not wait for a
// reopen: while the device is away it returns at once.
//
// Mounting: the IMU's axes need not be the body's. ImuMounting is the IMU-to-body
// rotation, body = R * imu with R = Rz(yaw) * Ry(pitch) * Rx(roll), angles in degrees,
// applied roll first: the same convention as the camera's mount angles (dsp/lens.h).
// ImuMountingFromAxes() turns an axis remap such as "x,-y,-z" (body x = IMU x, body y =
// -IMU y, body z = -IMU z: a board mounted upside down) into those angles. Read() applies
// R to both the accelerometer and the gyroscope of every sample.
#pragma once

#include <array>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <span>

#include "skyloc/drivers/stream_recovery.h"
#include "skyloc/dsp/imu.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// An IMU's reopen schedule after an outage: the camera's, with the attempts at most
// 500 ms apart instead of 2 s. Frames are described as if level while the IMU is away, so
// it must be back in use within a second of its return however long it was gone; an
// attempt is a scan of a few sysfs names, cheap enough twice a second for as long as it
// takes.
inline StreamRecoveryConfig ImuRecoveryConfig() {
  StreamRecoveryConfig c;
  c.backoff_max = std::chrono::milliseconds(500);
  return c;
}

struct ImuMounting {
  double roll_deg = 0.0;
  double pitch_deg = 0.0;
  double yaw_deg = 0.0;
};

// The rotation matrix (row-major, body = R * imu) of a mounting. kInvalidArgument when an
// angle is not finite.
Result<std::array<double, 9>> ImuMountingMatrix(const ImuMounting& mounting);

// Parses an axis remap: three comma-separated signed IMU axes, the i-th saying which IMU
// axis points along body axis i ("x,y,z" is the identity, "y,-x,z" a board turned 90 degrees
// clockwise seen from above). Each of x, y, z once; the remap must be a rotation (a
// right-handed IMU stays right-handed: "x,y,-z" is a mirror and is refused).
Result<ImuMounting> ImuMountingFromAxes(const char* axes);

struct ImuInfo {
  char name[64] = {};         // e.g. "iio:mpu6050", "sim:imu"
  double sample_rate_hz = 0;  // nominal rate (what the device reported or was set to)
  bool has_gyro = true;       // false: gyro_radps is always 0 (an accelerometer alone)
  char source[160] = {};      // how samples are read, e.g. "IIO buffer, trigger hrtimer0"
                              // or "sysfs polling: <why the buffer is not used>"
};

// Health counters every IMU keeps (the simulated twin too); the session prints them with
// the other devices' (firmware/device_report.h).
struct ImuCounters {
  std::uint64_t samples = 0;  // samples delivered by Read()
  std::uint64_t dropped = 0;  // samples lost (gaps in the timestamps, kernel FIFO overruns,
                              // polling ticks missed because Read() was called late)
  // Read() calls that returned an error other than a time-out or the end of a finite
  // source (as CameraCounters: how long to wait is the caller's choice, and the attitude
  // source asks for what is there).
  std::uint64_t errors = 0;
  std::uint64_t outages = 0;  // times the device was found gone and closed
  std::uint64_t reopens = 0;  // times it was reopened after an outage and streamed again
};

class ImuDevice {
 public:
  enum class State : std::uint8_t { kClosed, kOpen, kStreaming };

  virtual ~ImuDevice() = default;
  ImuDevice(const ImuDevice&) = delete;
  ImuDevice& operator=(const ImuDevice&) = delete;

  // Only while closed (kFailedPrecondition otherwise); kInvalidArgument for a non-finite
  // angle. Open() checks the mounting given at construction the same way.
  Status SetMounting(const ImuMounting& mounting);
  const ImuMounting& mounting() const { return mounting_; }

  Status Open();
  Status Start();
  // Waits up to `timeout` for at least one sample and writes every sample available, up to
  // out.size(), in the body frame, oldest first; returns how many. Timestamps strictly
  // increase (CLOCK_MONOTONIC for real devices). kDeadlineExceeded when none came in time;
  // kUnavailable when the device is gone (the errno is saved) and until it is reopened
  // (see Healing above); kInvalidArgument for an empty `out`. End of a finite source (the
  // simulated IMU's samples) is kOutOfRange.
  Result<std::size_t> Read(std::span<dsp::ImuSample> out, Nanoseconds timeout);
  void Stop();
  void Close();

  State state() const { return state_; }
  const ImuInfo& info() const { return info_; }
  const ImuCounters& counters() const { return counters_; }
  // The reopen schedule after an outage (kStreaming while the device is there).
  const StreamRecovery& recovery() const { return recovery_; }

 protected:
  // `clock` (nullptr: SystemMonotonicClock()) times the reopens; it must outlive the device.
  explicit ImuDevice(const ImuMounting& mounting = {}, const Clock* clock = nullptr,
                     const StreamRecoveryConfig& recovery = ImuRecoveryConfig())
      : mounting_(mounting),
        clock_(clock != nullptr ? clock : &SystemMonotonicClock()),
        recovery_config_(recovery),
        recovery_(recovery) {}
  const Clock& clock() const { return *clock_; }
  ImuInfo info_;
  ImuCounters counters_;

 private:
  virtual Status DoOpen() = 0;
  virtual Status DoStart() = 0;
  // Samples in the IMU's own frame; at least one and at most out.size() when OK.
  virtual Result<std::size_t> DoRead(std::span<dsp::ImuSample> out, Nanoseconds timeout) = 0;
  virtual void DoStop() = 0;
  virtual void DoClose() = 0;

  // The device was found gone: closed, the first reopen scheduled.
  void Lost();
  // Reopens the device when the backoff allows; kUnavailable (naming the IMU) until then.
  Status Reopen();

  ImuMounting mounting_;
  const Clock* clock_;
  StreamRecoveryConfig recovery_config_;
  StreamRecovery recovery_;
  Status last_reopen_error_;
  std::array<double, 9> rotation_{1, 0, 0, 0, 1, 0, 0, 0, 1};
  State state_ = State::kClosed;
};

const char* ImuStateName(ImuDevice::State state);

}  // namespace skyloc::drivers
