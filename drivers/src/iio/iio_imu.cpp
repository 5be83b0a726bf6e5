#include "skyloc/drivers/iio_imu.h"

#include <dirent.h>
#include <fcntl.h>
#include <poll.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string_view>

namespace skyloc::drivers {
namespace {

constexpr char kAxisNames[3] = {'x', 'y', 'z'};

// A real sleep of `d` (the clock may be a test's, which does not move by itself).
void SleepFor(Nanoseconds d) {
  if (d <= Nanoseconds(0))
    return;
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(d.count() / 1'000'000'000);
  ts.tv_nsec = static_cast<long>(d.count() % 1'000'000'000);
  while (::nanosleep(&ts, &ts) == -1 && errno == EINTR) {
  }
}

bool Exists(const char* path) {
  return ::access(path, F_OK) == 0;
}

// Reads a small sysfs attribute, without the trailing newline. -1 and errno on failure.
int ReadText(const char* path, char* text, std::size_t size) {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    return -1;
  ssize_t n = 0;
  do {
    n = ::read(fd, text, size - 1);
  } while (n < 0 && errno == EINTR);
  const int saved = errno;
  ::close(fd);
  if (n < 0) {
    errno = saved;
    return -1;
  }
  text[n] = '\0';
  while (n > 0 && (text[n - 1] == '\n' || text[n - 1] == ' '))
    text[--n] = '\0';
  return static_cast<int>(n);
}

// Writes a sysfs attribute. -1 and errno on failure.
int WriteText(const char* path, const char* text) {
  const int fd = ::open(path, O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0)
    return -1;
  const auto len = std::strlen(text);
  ssize_t n = 0;
  do {
    n = ::write(fd, text, len);
  } while (n < 0 && errno == EINTR);
  const int saved = errno;
  ::close(fd);
  if (n < 0) {
    errno = saved;
    return -1;
  }
  return 0;
}

bool ReadDouble(const char* path, double* value) {
  char text[64];
  if (ReadText(path, text, sizeof(text)) <= 0)
    return false;
  char* end = nullptr;
  const double v = std::strtod(text, &end);
  if (end == text || !std::isfinite(v))
    return false;
  *value = v;
  return true;
}

bool ReadInt(const char* path, long long* value) {
  char text[64];
  if (ReadText(path, text, sizeof(text)) <= 0)
    return false;
  char* end = nullptr;
  errno = 0;
  const long long v = std::strtoll(text, &end, 10);
  if (end == text || errno != 0)
    return false;
  *value = v;
  return true;
}

// Copies `src` to `dst`, or returns false when it does not fit.
bool Format(char* dst, std::size_t size, const char* format, ...)
    __attribute__((format(printf, 3, 4)));
bool Format(char* dst, std::size_t size, const char* format, ...) {
  va_list args;
  va_start(args, format);
  const int n = std::vsnprintf(dst, size, format, args);
  va_end(args);
  return n >= 0 && static_cast<std::size_t>(n) < size;
}

bool IsDeviceGoneErrno(int e) {
  return e == ENODEV || e == ENXIO || e == EIO || e == ENOENT || e == ESHUTDOWN || e == EBADF;
}

}  // namespace

Result<IioScanType> ParseIioScanType(const char* text) {
  IioScanType t;
  char endian[3] = {};
  char sign = 0;
  unsigned realbits = 0, storagebits = 0, repeat = 1, shift = 0;
  int consumed = 0;
  const char* p = text != nullptr ? text : "";
  if (std::sscanf(p, "%2[bel]:%c%u/%u%n", endian, &sign, &realbits, &storagebits, &consumed) != 4)
    consumed = -1;
  if (consumed > 0) {
    const char* rest = p + consumed;
    int more = 0;
    if (*rest == 'X') {
      if (std::sscanf(rest, "X%u%n", &repeat, &more) != 1)
        consumed = -1;
      rest += more;
    }
    if (consumed > 0 && *rest == '>') {
      more = 0;
      if (std::sscanf(rest, ">>%u%n", &shift, &more) != 1)
        consumed = -1;
      rest += more;
    }
    if (consumed > 0 && *rest != '\0' && *rest != '\n')
      consumed = -1;
  }
  const bool bad_endian = std::strcmp(endian, "le") != 0 && std::strcmp(endian, "be") != 0;
  if (consumed <= 0 || bad_endian || (sign != 's' && sign != 'u') ||
      (storagebits != 8 && storagebits != 16 && storagebits != 32 && storagebits != 64) ||
      realbits == 0 || realbits > storagebits || shift + realbits > storagebits || repeat == 0 ||
      repeat > 16) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "IIO scan element type '%s' is not of the form [be|le]:[s|u]bits/"
                         "storagebits[Xrepeat]>>shift (e.g. le:s16/16>>0)",
                         p);
  }
  t.big_endian = endian[0] == 'b';
  t.is_signed = sign == 's';
  t.realbits = static_cast<std::uint8_t>(realbits);
  t.storagebits = static_cast<std::uint8_t>(storagebits);
  t.shift = static_cast<std::uint8_t>(shift);
  t.repeat = static_cast<std::uint8_t>(repeat);
  return t;
}

std::int64_t IioScanValue(const IioScanType& type, const std::uint8_t* p) {
  const std::size_t bytes = type.storagebits / 8u;
  std::uint64_t raw = 0;
  for (std::size_t i = 0; i < bytes; ++i) {
    const std::size_t b = type.big_endian ? i : bytes - 1 - i;
    raw = (raw << 8) | p[b];
  }
  raw >>= type.shift;
  if (type.realbits < 64) {
    const std::uint64_t mask = (std::uint64_t{1} << type.realbits) - 1;
    raw &= mask;
    if (type.is_signed && (raw >> (type.realbits - 1)) != 0)
      raw |= ~mask;
  }
  return static_cast<std::int64_t>(raw);
}

IioImu::IioImu(const IioImuConfig& config, const Clock* clock)
    : ImuDevice(config.mounting, clock, config.recovery), config_(config) {
  config_.device[sizeof(config_.device) - 1] = '\0';
  config_.gyro_device[sizeof(config_.gyro_device) - 1] = '\0';
  config_.trigger[sizeof(config_.trigger) - 1] = '\0';
  config_.sysfs_root[sizeof(config_.sysfs_root) - 1] = '\0';
  config_.dev_root[sizeof(config_.dev_root) - 1] = '\0';
  std::snprintf(info_.name, sizeof(info_.name), "iio:%.58s", config_.device);
  info_.sample_rate_hz = config.sample_rate_hz;
}

Status IioImu::FindDevice(const char* spec, char* dir, std::size_t dir_size, int* number) const {
  const char* base = std::strrchr(spec, '/');
  base = base != nullptr ? base + 1 : spec;
  int n = -1;
  char tail = 0;
  if (std::sscanf(base, "iio:device%d%c", &n, &tail) == 1 && n >= 0) {
    if (!Format(dir, dir_size, "%s/iio:device%d", config_.sysfs_root, n)) {
      return Status::Error(StatusCode::kInvalidArgument, "imu %s: sysfs path too long", info_.name);
    }
    if (!Exists(dir)) {
      const int saved = errno;
      return Status::FromErrno(saved,
                               "imu %s: no IIO device %s (%s missing; is its kernel driver "
                               "loaded? ls /sys/bus/iio/devices)",
                               info_.name, base, dir);
    }
    *number = n;
    return Status::Ok();
  }
  if (spec[0] == '/') {
    return Status::Error(StatusCode::kInvalidArgument,
                         "imu device '%s' is a path but not /dev/iio:deviceN; give the IIO "
                         "character device or the device's sysfs name",
                         spec);
  }
  // By name: the lowest-numbered iio:deviceN whose name matches.
  DIR* d = ::opendir(config_.sysfs_root);
  if (d == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved,
                             "imu %s: cannot list IIO devices in %s (kernel without "
                             "CONFIG_IIO, or sysfs not mounted)",
                             info_.name, config_.sysfs_root);
  }
  char seen[96] = {};
  std::size_t seen_len = 0;
  int best = -1;
  while (const dirent* e = ::readdir(d)) {
    int m = -1;
    char extra = 0;
    if (std::sscanf(e->d_name, "iio:device%d%c", &m, &extra) != 1 || m < 0)
      continue;
    char path[320];
    char name[64];
    if (!Format(path, sizeof(path), "%s/%s/name", config_.sysfs_root, e->d_name) ||
        ReadText(path, name, sizeof(name)) < 0)
      continue;
    if (std::strcmp(name, spec) == 0) {
      if (best < 0 || m < best)
        best = m;
    } else if (seen_len + std::strlen(name) + 2 < sizeof(seen)) {
      seen_len += static_cast<std::size_t>(std::snprintf(seen + seen_len, sizeof(seen) - seen_len,
                                                         "%s%s", seen_len ? " " : "", name));
    }
  }
  ::closedir(d);
  if (best < 0) {
    return Status::Error(StatusCode::kNotFound,
                         "imu %s: no IIO device named '%s' in %s (present: %s); load the IMU's "
                         "kernel driver (check dmesg) or give /dev/iio:deviceN",
                         info_.name, spec, config_.sysfs_root, seen_len ? seen : "none");
  }
  Format(dir, dir_size, "%s/iio:device%d", config_.sysfs_root, best);
  *number = best;
  return Status::Ok();
}

Status IioImu::LoadAxes(const char* dir, const char* type, Axis* axes, bool required) {
  for (int i = 0; i < 3; ++i) {
    Axis& a = axes[i];
    a = Axis{};
    Format(a.raw_path, sizeof(a.raw_path), "%s/in_%s_%c_raw", dir, type, kAxisNames[i]);
    if (!Exists(a.raw_path)) {
      if (!required && i == 0)
        return Status::Error(StatusCode::kNotFound, "no %s", type);
      return Status::Error(
          StatusCode::kNotFound,
          "imu %s: %s has no %s (in_%s_x_raw, _y_raw, _z_raw; %s missing): %s", info_.name, dir,
          std::strcmp(type, "accel") == 0 ? "accelerometer" : "gyroscope", type, a.raw_path,
          std::strcmp(type, "accel") == 0
              ? "name the device with the accelerometer (LSM6DSx: the _accel one)"
              : "name the gyroscope's device in gyro_device, or leave it empty");
    }
  }
  for (int i = 0; i < 3; ++i) {
    Axis& a = axes[i];
    char path[320];
    Format(path, sizeof(path), "%s/in_%s_%c_scale", dir, type, kAxisNames[i]);
    if (!ReadDouble(path, &a.scale)) {
      Format(path, sizeof(path), "%s/in_%s_scale", dir, type);
      if (!ReadDouble(path, &a.scale)) {
        return Status::Error(StatusCode::kNotFound,
                             "imu %s: %s has no readable in_%s_scale or in_%s_%c_scale, so its "
                             "raw values cannot be converted to %s; is this an IIO IMU driver?",
                             info_.name, dir, type, type, kAxisNames[i],
                             std::strcmp(type, "accel") == 0 ? "m/s^2" : "rad/s");
      }
    }
    Format(path, sizeof(path), "%s/in_%s_%c_offset", dir, type, kAxisNames[i]);
    if (!ReadDouble(path, &a.offset)) {
      Format(path, sizeof(path), "%s/in_%s_offset", dir, type);
      if (!ReadDouble(path, &a.offset))
        a.offset = 0.0;
    }
  }
  return Status::Ok();
}

Status IioImu::OpenDevices() {
  if (!(config_.sample_rate_hz > 0.0 && config_.sample_rate_hz <= 100'000.0)) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "imu %s: sample_rate_hz %g is outside (0, 100000]", info_.name,
                         config_.sample_rate_hz);
  }
  if (config_.device[0] == '\0') {
    return Status::Error(StatusCode::kInvalidArgument,
                         "imu: no IIO device named: set the device (/dev/iio:deviceN or its "
                         "sysfs name, e.g. mpu6050)");
  }
  SKYLOC_TRY(FindDevice(config_.device, accel_dir_, sizeof(accel_dir_), &accel_number_));
  SKYLOC_TRY(LoadAxes(accel_dir_, "accel", accel_, true));
  info_.has_gyro = true;
  if (config_.gyro_device[0] != '\0') {
    int gyro_number = -1;
    SKYLOC_TRY(FindDevice(config_.gyro_device, gyro_dir_, sizeof(gyro_dir_), &gyro_number));
    SKYLOC_TRY(LoadAxes(gyro_dir_, "anglvel", gyro_, true));
  } else {
    std::snprintf(gyro_dir_, sizeof(gyro_dir_), "%s", accel_dir_);
    Status s = LoadAxes(gyro_dir_, "anglvel", gyro_, false);
    if (!s.ok()) {
      char probe[320];
      Format(probe, sizeof(probe), "%s/in_anglvel_x_raw", gyro_dir_);
      if (Exists(probe))
        return s;  // a gyroscope, but an unusable one
      info_.has_gyro = false;
      gyro_dir_[0] = '\0';
    }
  }
  Format(node_, sizeof(node_), "%s/iio:device%d", config_.dev_root, accel_number_);
  return Status::Ok();
}

void IioImu::BufferUnusableReason(char* reason, std::size_t size) const {
  reason[0] = '\0';
  char path[320];
  if (config_.mode == IioImuConfig::Mode::kPolling) {
    std::snprintf(reason, size, "mode is polling");
    return;
  }
  if (info_.has_gyro && std::strcmp(gyro_dir_, accel_dir_) != 0) {
    std::snprintf(reason, size,
                  "accelerometer and gyroscope are separate IIO devices (merging two buffers "
                  "is not supported)");
    return;
  }
  Format(path, sizeof(path), "%s/scan_elements/in_accel_x_en", accel_dir_);
  if (!Exists(path)) {
    std::snprintf(reason, size, "%.100s has no scan_elements (no buffer support)", accel_dir_);
    return;
  }
  Format(path, sizeof(path), "%s/buffer/enable", accel_dir_);
  if (!Exists(path)) {
    std::snprintf(reason, size, "%.100s has no buffer/enable", accel_dir_);
    return;
  }
  if (!Exists(node_)) {
    std::snprintf(reason, size, "no character device %.100s", node_);
    return;
  }
  if (config_.trigger[0] == '\0') {
    Format(path, sizeof(path), "%s/trigger/current_trigger", accel_dir_);
    char current[64] = {};
    if (Exists(path) && ReadText(path, current, sizeof(current)) <= 0) {
      std::snprintf(reason, size,
                    "no trigger attached to %.80s (set trigger, e.g. an hrtimer trigger)",
                    accel_dir_);
      return;
    }
  }
}

Status IioImu::SetUpBuffer() {
  char path[320];
  // The driver takes the device over: a buffer left enabled (by a crashed run) is disabled.
  Format(path, sizeof(path), "%s/buffer/enable", accel_dir_);
  if (WriteText(path, "0") != 0) {
    const int saved = errno;
    return Status::FromErrno(saved,
                             "imu %s: cannot write 0 to %s (run as root, or give the "
                             "user write access to the IIO sysfs files)",
                             info_.name, path);
  }
  Format(path, sizeof(path), "%s/current_timestamp_clock", accel_dir_);
  const bool monotonic_clock = Exists(path) && WriteText(path, "monotonic") == 0;

  // Enable our channels, disable the rest.
  Format(path, sizeof(path), "%s/scan_elements", accel_dir_);
  DIR* d = ::opendir(path);
  if (d == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "imu %s: cannot list %s", info_.name, path);
  }
  Status failed;
  while (const dirent* e = ::readdir(d)) {
    const std::size_t len = std::strlen(e->d_name);
    if (len < 4 || std::strcmp(e->d_name + len - 3, "_en") != 0)
      continue;
    const std::string_view channel(e->d_name, len - 3);
    bool wanted = channel == "in_timestamp" ? monotonic_clock : false;
    for (int i = 0; i < 3; ++i) {
      char ours[32];
      std::snprintf(ours, sizeof(ours), "in_accel_%c", kAxisNames[i]);
      wanted = wanted || channel == ours;
      std::snprintf(ours, sizeof(ours), "in_anglvel_%c", kAxisNames[i]);
      wanted = wanted || (info_.has_gyro && channel == ours);
    }
    char en[320];
    Format(en, sizeof(en), "%s/scan_elements/%s", accel_dir_, e->d_name);
    if (WriteText(en, wanted ? "1" : "0") != 0 && wanted && failed.ok()) {
      const int saved = errno;
      failed = Status::FromErrno(saved, "imu %s: cannot enable %s", info_.name, en);
    }
  }
  ::closedir(d);
  SKYLOC_TRY(failed);

  // The scan layout, as the kernel computes it: enabled elements in index order, each
  // aligned to its own size, the scan padded to the largest.
  element_count_ = 0;
  timestamp_element_ = -1;
  d = ::opendir(path);
  if (d == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "imu %s: cannot list %s", info_.name, path);
  }
  while (const dirent* e = ::readdir(d)) {
    const std::size_t len = std::strlen(e->d_name);
    if (len < 4 || std::strcmp(e->d_name + len - 3, "_en") != 0)
      continue;
    char file[320];
    Format(file, sizeof(file), "%s/scan_elements/%s", accel_dir_, e->d_name);
    long long enabled = 0;
    if (!ReadInt(file, &enabled) || enabled == 0)
      continue;
    if (element_count_ == kMaxScanElements || len - 3 >= sizeof(Element{}.channel)) {
      failed = Status::Error(StatusCode::kResourceExhausted,
                             "imu %s: more than %zu scan elements enabled in %s", info_.name,
                             kMaxScanElements, path);
      break;
    }
    Element& el = elements_[element_count_];
    el = Element{};
    std::memcpy(el.channel, e->d_name, len - 3);
    long long index = 0;
    Format(file, sizeof(file), "%s/scan_elements/%s_index", accel_dir_, el.channel);
    char type_text[64];
    char type_file[320];
    Format(type_file, sizeof(type_file), "%s/scan_elements/%s_type", accel_dir_, el.channel);
    if (!ReadInt(file, &index) || index < 0 ||
        ReadText(type_file, type_text, sizeof(type_text)) <= 0) {
      failed = Status::Error(StatusCode::kDataLoss, "imu %s: cannot read %s or %s", info_.name,
                             file, type_file);
      break;
    }
    Result<IioScanType> type = ParseIioScanType(type_text);
    if (!type.ok()) {
      failed = type.status();
      failed.AddContext("imu %s: %s", info_.name, type_file);
      break;
    }
    el.index = static_cast<int>(index);
    el.type = *type;
    ++element_count_;
  }
  ::closedir(d);
  SKYLOC_TRY(failed);
  std::sort(elements_, elements_ + element_count_,
            [](const Element& a, const Element& b) { return a.index < b.index; });
  std::size_t offset = 0;
  std::size_t largest = 1;
  for (std::size_t i = 0; i < element_count_; ++i) {
    const std::size_t bytes = elements_[i].type.bytes();
    offset = (offset + bytes - 1) / bytes * bytes;
    elements_[i].offset = offset;
    offset += bytes;
    largest = std::max(largest, bytes);
    if (std::strcmp(elements_[i].channel, "in_timestamp") == 0)
      timestamp_element_ = static_cast<int>(i);
    for (int a = 0; a < 3; ++a) {
      char name[32];
      std::snprintf(name, sizeof(name), "in_accel_%c", kAxisNames[a]);
      if (std::strcmp(elements_[i].channel, name) == 0)
        accel_[a].element = static_cast<int>(i);
      std::snprintf(name, sizeof(name), "in_anglvel_%c", kAxisNames[a]);
      if (info_.has_gyro && std::strcmp(elements_[i].channel, name) == 0)
        gyro_[a].element = static_cast<int>(i);
    }
  }
  scan_bytes_ = (offset + largest - 1) / largest * largest;
  for (int a = 0; a < 3; ++a) {
    if (accel_[a].element < 0 || (info_.has_gyro && gyro_[a].element < 0)) {
      return Status::Error(StatusCode::kFailedPrecondition,
                           "imu %s: the %s axis did not stay enabled in %s/scan_elements",
                           info_.name, accel_[a].element < 0 ? "accelerometer" : "gyroscope",
                           accel_dir_);
    }
  }
  if (timestamp_element_ >= 0 && elements_[timestamp_element_].type.storagebits != 64)
    timestamp_element_ = -1;

  // The kernel FIFO: one second's worth of scans, at least 64.
  std::uint32_t length = config_.buffer_length;
  if (length == 0)
    length = std::max<std::uint32_t>(64, static_cast<std::uint32_t>(config_.sample_rate_hz));
  Format(path, sizeof(path), "%s/buffer/length", accel_dir_);
  char text[32];
  std::snprintf(text, sizeof(text), "%u", length);
  if (WriteText(path, text) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "imu %s: cannot write %s", info_.name, path);
  }
  SKYLOC_TRY(scan_buffer_.Allocate(scan_bytes_ * kScansPerRead));

  // The trigger, by name.
  trigger_dir_[0] = '\0';
  if (config_.trigger[0] != '\0') {
    DIR* td = ::opendir(config_.sysfs_root);
    if (td != nullptr) {
      while (const dirent* e = ::readdir(td)) {
        if (std::strncmp(e->d_name, "trigger", 7) != 0)
          continue;
        char file[320];
        char name[64];
        Format(file, sizeof(file), "%s/%s/name", config_.sysfs_root, e->d_name);
        if (ReadText(file, name, sizeof(name)) > 0 && std::strcmp(name, config_.trigger) == 0) {
          Format(trigger_dir_, sizeof(trigger_dir_), "%s/%s", config_.sysfs_root, e->d_name);
          break;
        }
      }
      ::closedir(td);
    }
    if (trigger_dir_[0] == '\0') {
      return Status::Error(StatusCode::kNotFound,
                           "imu %s: no IIO trigger named '%s' in %s (create it, e.g. mkdir "
                           "/sys/kernel/config/iio/triggers/hrtimer/%s, or leave trigger empty)",
                           info_.name, config_.trigger, config_.sysfs_root, config_.trigger);
    }
    Format(path, sizeof(path), "%s/trigger/current_trigger", accel_dir_);
    if (WriteText(path, config_.trigger) != 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "imu %s: cannot attach trigger '%s' (write %s)", info_.name,
                               config_.trigger, path);
    }
  }

  const int fd = ::open(node_, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    const int saved = errno;
    return Status::FromErrno(saved,
                             "imu %s: cannot open %s (EBUSY: another program has it open; "
                             "EACCES: run as root or add a udev rule)",
                             info_.name, node_);
  }
  node_fd_.reset(fd);
  std::snprintf(info_.source, sizeof(info_.source), "IIO buffer %.60s%s%.40s%s", node_,
                config_.trigger[0] != '\0' ? ", trigger " : "", config_.trigger,
                timestamp_element_ >= 0 ? "" : ", stamped when read");
  return Status::Ok();
}

Status IioImu::SetUpPolling() {
  for (Axis* axes : {accel_, gyro_}) {
    if (axes == gyro_ && !info_.has_gyro)
      continue;
    for (int i = 0; i < 3; ++i) {
      const int fd = ::open(axes[i].raw_path, O_RDONLY | O_CLOEXEC);
      if (fd < 0) {
        const int saved = errno;
        return Status::FromErrno(saved, "imu %s: cannot open %s", info_.name, axes[i].raw_path);
      }
      axes[i].raw_fd.reset(fd);
    }
  }
  return Status::Ok();
}

Status IioImu::DoOpen() {
  gone_ = false;
  have_last_ = false;
  carry_ = 0;
  buffered_ = false;
  buffer_enabled_ = false;
  element_count_ = 0;
  Status s = OpenDevices();
  if (s.ok()) {
    period_ = Nanoseconds(static_cast<std::int64_t>(1e9 / config_.sample_rate_hz));
    char reason[160];
    BufferUnusableReason(reason, sizeof(reason));
    if (reason[0] == '\0') {
      s = SetUpBuffer();
      if (s.ok())
        buffered_ = true;
      else if (config_.mode == IioImuConfig::Mode::kAuto)
        std::snprintf(reason, sizeof(reason), "%.150s", s.message());
    } else if (config_.mode == IioImuConfig::Mode::kBuffer) {
      s = Status::Error(StatusCode::kFailedPrecondition,
                        "imu %s: mode is buffer, but the IIO buffer cannot be used: %s", info_.name,
                        reason);
    }
    if (!buffered_ && config_.mode != IioImuConfig::Mode::kBuffer) {
      node_fd_.reset();
      s = SetUpPolling();
      if (s.ok()) {
        std::snprintf(info_.source, sizeof(info_.source), "sysfs polling at %g Hz: %.120s",
                      config_.sample_rate_hz, reason);
        if (!logged_fallback_ && config_.mode == IioImuConfig::Mode::kAuto) {
          std::fprintf(stderr, "imu %s: %s\n", info_.name, info_.source);
          logged_fallback_ = true;
        }
      }
    }
  }
  if (!s.ok())
    DoClose();
  return s;
}

Status IioImu::DoStart() {
  carry_ = 0;
  char path[320];
  char text[32];
  std::snprintf(text, sizeof(text), "%g", config_.sample_rate_hz);
  // The rate: the trigger's (hrtimer) and the device's, where writable (best effort: many
  // devices accept only some rates and round; what they report is taken).
  double rate = 0;
  if (trigger_dir_[0] != '\0') {
    Format(path, sizeof(path), "%s/sampling_frequency", trigger_dir_);
    if (Exists(path)) {
      (void)WriteText(path, text);
      if (!ReadDouble(path, &rate))
        rate = 0;
    }
  }
  Format(path, sizeof(path), "%s/sampling_frequency", accel_dir_);
  if (Exists(path)) {
    (void)WriteText(path, text);
    double device_rate = 0;
    if (rate == 0 && ReadDouble(path, &device_rate))
      rate = device_rate;
  }
  if (!buffered_)
    rate = config_.sample_rate_hz;
  if (rate > 0) {
    info_.sample_rate_hz = rate;
    period_ = Nanoseconds(static_cast<std::int64_t>(1e9 / rate));
  }
  if (buffered_) {
    Format(path, sizeof(path), "%s/buffer/enable", accel_dir_);
    if (WriteText(path, "1") != 0) {
      const int saved = errno;
      return Status::FromErrno(saved,
                               "imu %s: cannot enable the buffer (write 1 to %s); is a trigger "
                               "attached (trigger/current_trigger)?",
                               info_.name, path);
    }
    buffer_enabled_ = true;
  } else {
    next_tick_ = clock().Now();
  }
  return Status::Ok();
}

Status IioImu::Gone(int saved_errno, const char* what) {
  gone_ = true;
  // Always kUnavailable: a sysfs file that vanished (ENOENT) means the device went too.
  if (StatusCodeFromErrno(saved_errno) != StatusCode::kUnavailable) {
    return Status::FromErrno(ENODEV,
                             "imu %s: %s: %s, so the IMU is gone (unplugged, driver unbound or "
                             "crashed); reopening it when it is back",
                             info_.name, what, std::strerror(saved_errno));
  }
  return Status::FromErrno(saved_errno,
                           "imu %s: %s: the IMU is gone (unplugged, driver unbound or "
                           "crashed); reopening it when it is back",
                           info_.name, what);
}

bool IioImu::Deliver(dsp::ImuSample* sample) {
  if (have_last_) {
    const std::int64_t delta = sample->timestamp_ns - last_ns_;
    if (delta <= 0) {
      ++counters_.dropped;
      return false;
    }
    const std::int64_t period = period_.count();
    if (period > 0 && delta > period + period / 2)
      counters_.dropped += static_cast<std::uint64_t>((delta + period / 2) / period - 1);
  }
  have_last_ = true;
  last_ns_ = sample->timestamp_ns;
  return true;
}

std::size_t IioImu::DecodeScans(const std::uint8_t* data, std::size_t scans,
                                std::span<dsp::ImuSample> out, Nanoseconds read_time) {
  std::size_t n = 0;
  for (std::size_t i = 0; i < scans && n < out.size(); ++i) {
    const std::uint8_t* scan = data + i * scan_bytes_;
    dsp::ImuSample s;
    for (int a = 0; a < 3; ++a) {
      const Element& ea = elements_[accel_[a].element];
      s.accel_mps2[static_cast<std::size_t>(a)] = static_cast<float>(
          (static_cast<double>(IioScanValue(ea.type, scan + ea.offset)) + accel_[a].offset) *
          accel_[a].scale);
      if (info_.has_gyro) {
        const Element& eg = elements_[gyro_[a].element];
        s.gyro_radps[static_cast<std::size_t>(a)] = static_cast<float>(
            (static_cast<double>(IioScanValue(eg.type, scan + eg.offset)) + gyro_[a].offset) *
            gyro_[a].scale);
      }
    }
    if (timestamp_element_ >= 0) {
      const Element& et = elements_[timestamp_element_];
      s.timestamp_ns = IioScanValue(et.type, scan + et.offset);
    } else {
      s.timestamp_ns = (read_time - period_ * static_cast<std::int64_t>(scans - 1 - i)).count();
    }
    if (Deliver(&s))
      out[n++] = s;
  }
  return n;
}

Result<std::size_t> IioImu::ReadBuffer(std::span<dsp::ImuSample> out, Nanoseconds timeout) {
  const Nanoseconds deadline = clock().Now() + timeout;
  const std::size_t want = std::min(out.size(), kScansPerRead);
  bool waited_out = false;
  for (;;) {
    const std::size_t room = want * scan_bytes_ - carry_;
    const ssize_t r = ::read(node_fd_.get(), scan_buffer_.data() + carry_, room);
    if (r > 0) {
      const std::size_t total = carry_ + static_cast<std::size_t>(r);
      const std::size_t scans = total / scan_bytes_;
      const std::size_t n = DecodeScans(scan_buffer_.data(), scans, out, clock().Now());
      carry_ = total - scans * scan_bytes_;
      if (carry_ > 0)
        std::memmove(scan_buffer_.data(), scan_buffer_.data() + scans * scan_bytes_, carry_);
      if (n > 0)
        return n;
      continue;
    }
    if (r == 0)
      return Gone(ENODEV, node_);  // end of file: the device (or its stand-in) went away
    const int saved = errno;
    if (saved == EINTR)
      continue;
    if (saved != EAGAIN && saved != EWOULDBLOCK) {
      if (IsDeviceGoneErrno(saved))
        return Gone(saved, node_);
      return Status::FromErrno(saved, "imu %s: reading %s", info_.name, node_);
    }
    const Nanoseconds remaining = deadline - clock().Now();
    if (remaining <= Nanoseconds(0) || waited_out) {
      return Status::Error(StatusCode::kDeadlineExceeded,
                           "imu %s: no sample from %s within %lld ms (is the trigger running? "
                           "%s)",
                           info_.name, node_, static_cast<long long>(timeout.count() / 1'000'000),
                           info_.source);
    }
    pollfd pfd{node_fd_.get(), POLLIN, 0};
    const int p = ::poll(&pfd, 1, PollTimeoutMs(remaining));
    if (p < 0 && errno != EINTR) {
      const int e = errno;
      return Status::FromErrno(e, "imu %s: poll on %s", info_.name, node_);
    }
    // Ready, timed out or hung up: the next read() says which (an unregistered IIO device
    // does not wake poll(); its read() fails with ENODEV). A poll that ran its whole time
    // ends the wait after that read, whatever the clock says (a ManualClock stands still).
    waited_out = p == 0;
  }
}

Result<std::size_t> IioImu::ReadPolled(std::span<dsp::ImuSample> out, Nanoseconds timeout) {
  char name_path[320];
  Format(name_path, sizeof(name_path), "%s/name", accel_dir_);
  if (::access(name_path, F_OK) != 0) {
    const int saved = errno;
    return Gone(saved, name_path);
  }
  Nanoseconds now = clock().Now();
  if (next_tick_ > now) {
    if (next_tick_ > now + timeout) {
      SleepFor(timeout);
      return Status::Error(StatusCode::kDeadlineExceeded,
                           "imu %s: next polled sample is due after the %lld ms timeout",
                           info_.name, static_cast<long long>(timeout.count() / 1'000'000));
    }
    SleepFor(next_tick_ - now);
    // At the tick at least: a ManualClock does not move while the driver sleeps.
    now = std::max(clock().Now(), next_tick_);
  }
  dsp::ImuSample s;
  for (Axis* axes : {accel_, gyro_}) {
    if (axes == gyro_ && !info_.has_gyro)
      continue;
    for (int i = 0; i < 3; ++i) {
      char text[40];
      ssize_t r = 0;
      do {
        r = ::pread(axes[i].raw_fd.get(), text, sizeof(text) - 1, 0);
      } while (r < 0 && errno == EINTR);
      if (r < 0) {
        const int saved = errno;
        if (IsDeviceGoneErrno(saved))
          return Gone(saved, axes[i].raw_path);
        return Status::FromErrno(saved, "imu %s: reading %s", info_.name, axes[i].raw_path);
      }
      text[r] = '\0';
      char* end = nullptr;
      const long long raw = std::strtoll(text, &end, 10);
      if (end == text) {
        return Status::Error(StatusCode::kDataLoss, "imu %s: %s reads '%.20s', not an integer",
                             info_.name, axes[i].raw_path, text);
      }
      const float v =
          static_cast<float>((static_cast<double>(raw) + axes[i].offset) * axes[i].scale);
      (axes == accel_ ? s.accel_mps2 : s.gyro_radps)[static_cast<std::size_t>(i)] = v;
    }
  }
  s.timestamp_ns = std::max(clock().Now(), now).count();
  // Ticks that passed while nobody was reading are lost, not made up.
  const std::int64_t late = (now - next_tick_).count();
  const std::int64_t period = period_.count();
  const std::int64_t missed = late > 0 ? late / period : 0;
  next_tick_ += period_ * (missed + 1);
  counters_.dropped += static_cast<std::uint64_t>(missed);
  if (s.timestamp_ns <= last_ns_)
    s.timestamp_ns = last_ns_ + 1;
  last_ns_ = s.timestamp_ns;
  out[0] = s;
  return std::size_t{1};
}

Result<std::size_t> IioImu::DoRead(std::span<dsp::ImuSample> out, Nanoseconds timeout) {
  if (gone_) {
    return Status::Error(StatusCode::kUnavailable,
                         "imu %s: the IMU is gone; reopening it when it is back", info_.name);
  }
  return buffered_ ? ReadBuffer(out, timeout) : ReadPolled(out, timeout);
}

void IioImu::DisableBuffer() {
  if (!buffer_enabled_)
    return;
  char path[320];
  Format(path, sizeof(path), "%s/buffer/enable", accel_dir_);
  (void)WriteText(path, "0");  // the device may be gone: nothing left to disable then
  buffer_enabled_ = false;
}

void IioImu::DoStop() {
  DisableBuffer();
}

void IioImu::DoClose() {
  DisableBuffer();
  node_fd_.reset();
  for (Axis* axes : {accel_, gyro_}) {
    for (int i = 0; i < 3; ++i)
      axes[i].raw_fd.reset();
  }
}

}  // namespace skyloc::drivers
