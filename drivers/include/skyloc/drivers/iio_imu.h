// An IMU through the Linux IIO subsystem (MPU-6050, BMI160, LSM6DSx, the kernel's
// iio_dummy ...): an accelerometer (in_accel_{x,y,z}_raw) and optionally a gyroscope
// (in_anglvel_{x,y,z}_raw), on one IIO device or on two (LSM6DSx registers the
// accelerometer and the gyroscope as separate devices: name the second in gyro_device).
// Needs only sysfs and the /dev/iio:deviceN character device, no library.
//
// Samples come from the IIO buffer when it can be used: scan elements enabled for the six
// axes and the timestamp (everything else disabled), buffer/length, the configured trigger
// written to trigger/current_trigger (or the device's own / none for devices with a
// hardware FIFO), buffer/enable, then read() on the character device. Otherwise (no
// scan_elements, no trigger attached, accelerometer and gyroscope on two devices, or
// mode = kPolling) the driver polls the _raw attributes at sample_rate_hz, and says why in
// info().source and once on stderr. Values are (raw + offset) * scale, in m/s^2 and rad/s.
//
// Timestamps are CLOCK_MONOTONIC: the driver writes "monotonic" to current_timestamp_clock
// and uses the buffer's timestamp channel when both exist; otherwise a sample is stamped
// with the driver's Clock when it was read (a batch spaced one period apart, ending now).
// The Clock (SystemMonotonicClock() unless one is given) also times Read()'s timeout, the
// polling ticks and the reopens after an outage (ImuDevice), so a test drives them all
// with a ManualClock. Waits are real (poll(), a sleep until the next polling tick): under a
// ManualClock a test moves the clock before it reads, and a wait that runs out ends the
// Read() whatever the clock says.
//
// The sysfs and /dev roots are configurable so tests run the driver over a fake tree in a
// scratch folder, with a FIFO standing in for the character device (tests/drivers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

#include "skyloc/drivers/imu_device.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/status.h"
#include "skyloc/platform/unique_fd.h"

namespace skyloc::drivers {

// One scan element's storage, from scan_elements/<channel>_type: "[be|le]:[s|u]bits/
// storagebits[Xrepeat][>>shift]", e.g. "le:s16/16>>0", "be:u12/16>>4", "le:s64/64>>0".
struct IioScanType {
  bool big_endian = false;
  bool is_signed = false;
  std::uint8_t realbits = 0;
  std::uint8_t storagebits = 0;  // 8, 16, 32 or 64
  std::uint8_t shift = 0;
  std::uint8_t repeat = 1;
  std::size_t bytes() const { return static_cast<std::size_t>(storagebits / 8) * repeat; }
};
Result<IioScanType> ParseIioScanType(const char* text);
// The (first) value of a scan element stored at `p`: shifted, masked, sign-extended.
std::int64_t IioScanValue(const IioScanType& type, const std::uint8_t* p);

struct IioImuConfig {
  // "/dev/iio:deviceN", "iio:deviceN", or the device's sysfs name ("mpu6050", "bmi160",
  // "lsm6dsl_accel", "iio_dummy_part_no"); the first device with that name is taken.
  char device[128] = "";
  // The gyroscope's device when it is not `device` (LSM6DSx: "lsm6dsl_gyro"); empty: the
  // gyroscope is on `device`, or there is none (has_gyro false, gyro reads 0).
  char gyro_device[128] = "";
  // A trigger name (/sys/bus/iio/devices/triggerN/name) to attach before enabling the
  // buffer, e.g. an hrtimer trigger created in configfs or the device's own "mpu6050-dev0";
  // empty: keep whatever is attached (devices with a hardware FIFO need none).
  char trigger[64] = "";
  // Written to the trigger's sampling_frequency (hrtimer) and the device's when they are
  // writable; the polling rate without the buffer.
  double sample_rate_hz = 100.0;
  enum class Mode : std::uint8_t { kAuto, kBuffer, kPolling };
  Mode mode = Mode::kAuto;  // kBuffer: fail instead of polling when the buffer cannot be used
  std::uint32_t buffer_length = 0;  // kernel FIFO, scans; 0: one second's worth, at least 64
  char sysfs_root[192] = "/sys/bus/iio/devices";
  char dev_root[192] = "/dev";
  ImuMounting mounting;
  // Reopening after an outage (ImuDevice).
  StreamRecoveryConfig recovery = ImuRecoveryConfig();
};

class IioImu final : public ImuDevice {
 public:
  static constexpr std::size_t kMaxScanElements = 32;
  static constexpr std::size_t kScansPerRead = 64;

  // `clock` (nullptr: SystemMonotonicClock()) must outlive the driver.
  explicit IioImu(const IioImuConfig& config, const Clock* clock = nullptr);
  ~IioImu() override { Close(); }

  bool buffered() const { return buffered_; }

 private:
  struct Axis {
    UniqueFd raw_fd;  // polling
    char raw_path[256] = {};
    double scale = 1.0;
    double offset = 0.0;
    int element = -1;  // index into elements_ (buffer)
  };
  struct Element {
    char channel[48] = {};  // e.g. "in_accel_x"
    int index = 0;
    IioScanType type;
    std::size_t offset = 0;  // in the scan, bytes
  };

  Status DoOpen() override;
  Status DoStart() override;
  Result<std::size_t> DoRead(std::span<dsp::ImuSample> out, Nanoseconds timeout) override;
  void DoStop() override;
  void DoClose() override;

  Status OpenDevices();
  Status FindDevice(const char* spec, char* dir, std::size_t dir_size, int* number) const;
  Status LoadAxes(const char* dir, const char* type, Axis* axes, bool required);
  // Empty when the buffer can be used; else why not.
  void BufferUnusableReason(char* reason, std::size_t size) const;
  Status SetUpBuffer();
  Status SetUpPolling();
  Result<std::size_t> ReadBuffer(std::span<dsp::ImuSample> out, Nanoseconds timeout);
  Result<std::size_t> ReadPolled(std::span<dsp::ImuSample> out, Nanoseconds timeout);
  std::size_t DecodeScans(const std::uint8_t* data, std::size_t scans,
                          std::span<dsp::ImuSample> out, Nanoseconds read_time);
  bool Deliver(dsp::ImuSample* sample);  // drop accounting; false: not strictly increasing
  Status Gone(int saved_errno, const char* what);
  void DisableBuffer();

  IioImuConfig config_;
  char accel_dir_[256] = {};
  char gyro_dir_[256] = {};
  char node_[256] = {};
  char trigger_dir_[256] = {};
  int accel_number_ = -1;
  Axis accel_[3];
  Axis gyro_[3];
  bool buffered_ = false;
  bool logged_fallback_ = false;
  bool gone_ = false;
  bool buffer_enabled_ = false;
  Nanoseconds period_{10'000'000};

  // Buffer.
  UniqueFd node_fd_;
  Element elements_[kMaxScanElements];
  std::size_t element_count_ = 0;
  int timestamp_element_ = -1;
  std::size_t scan_bytes_ = 0;
  FixedArray<std::uint8_t> scan_buffer_;
  std::size_t carry_ = 0;  // bytes of an incomplete scan kept at the buffer's start

  // Polling.
  Nanoseconds next_tick_{0};

  bool have_last_ = false;
  std::int64_t last_ns_ = 0;
};

}  // namespace skyloc::drivers
