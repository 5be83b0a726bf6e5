// A fake IIO IMU in a scratch folder, for the real IioImu driver: the sysfs tree of an
// MPU-6050-like device (sys/bus/iio/devices/iio:deviceN: name, in_accel_*, in_anglvel_*,
// in_temp_*, scan_elements, buffer, trigger, current_timestamp_clock; trigger0 an hrtimer
// trigger) and a FIFO standing in for /dev/iio:deviceN. Like the kernel, Produce() writes
// scans only while buffer/enable is 1 and the trigger is attached, laid out from the
// scan_elements the driver enabled (independently of the driver's own layout code), and
// stamps them with CLOCK_REALTIME unless the driver selected "monotonic". Single-threaded:
// the test calls Produce() before it reads, so nothing depends on timing.
#pragma once

#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace skyloc::drivers::testing {

class FakeIioDevice {
 public:
  struct Options {
    std::string name = "fake_imu";
    int number = 2;
    bool buffer = true;  // scan_elements, buffer/, trigger/ and a trigger
    bool gyro = true;
  };
  // A still, level IMU: +1 g on z (16399 * 0.000598 = 9.8066 m/s^2), a small gyro bias
  // different on every axis (rad/s), so axis mix-ups show.
  std::array<int, 3> accel_raw{0, 0, 16399};
  std::array<int, 3> gyro_raw{10, -20, 30};
  static constexpr double kAccelScale = 0.000598;
  static constexpr double kGyroScale = 0.001;

  FakeIioDevice(const std::string& root, Options options) : root_(root), options_(options) {
    Create();
  }
  ~FakeIioDevice() {
    if (writer_ >= 0)
      ::close(writer_);
  }
  FakeIioDevice(const FakeIioDevice&) = delete;
  FakeIioDevice& operator=(const FakeIioDevice&) = delete;

  std::string sysfs_root() const { return root_ + "/sys/bus/iio/devices"; }
  std::string dev_root() const { return root_ + "/dev"; }
  std::string dir() const { return sysfs_root() + "/iio:device" + std::to_string(options_.number); }
  std::string node() const { return dev_root() + "/iio:device" + std::to_string(options_.number); }
  std::string Get(const std::string& rel) const {
    std::ifstream f(dir() + "/" + rel);
    std::string s;
    std::getline(f, s);
    return s;
  }
  void Put(const std::string& path, const std::string& text) const {
    std::ofstream(path) << text << "\n";
  }

  // Writes `n` scans into the character device, as the kernel would; returns how many
  // (0 while the buffer is disabled or no trigger is attached).
  int Produce(int n) {
    if (writer_ < 0 || Get("buffer/enable") != "1" || Get("trigger/current_trigger") != "faketrig")
      return 0;
    struct El {
      std::string channel;
      int index;
      bool be;
      int bytes;
    };
    std::vector<El> els;
    for (const auto& e : std::filesystem::directory_iterator(dir() + "/scan_elements")) {
      const std::string f = e.path().filename().string();
      if (f.size() < 4 || f.compare(f.size() - 3, 3, "_en") != 0 ||
          Get("scan_elements/" + f) != "1")
        continue;
      const std::string ch = f.substr(0, f.size() - 3);
      const std::string type = Get("scan_elements/" + ch + "_type");
      els.push_back({ch, std::stoi(Get("scan_elements/" + ch + "_index")), type.rfind("be", 0) == 0,
                     std::stoi(type.substr(type.find('/') + 1)) / 8});
    }
    std::sort(els.begin(), els.end(), [](const El& a, const El& b) { return a.index < b.index; });
    std::size_t size = 0, largest = 1;
    std::vector<std::size_t> offsets;
    for (const El& e : els) {
      const auto b = static_cast<std::size_t>(e.bytes);
      size = (size + b - 1) / b * b;
      offsets.push_back(size);
      size += b;
      largest = std::max(largest, b);
    }
    size = (size + largest - 1) / largest * largest;
    const bool mono = Get("current_timestamp_clock") == "monotonic";
    const std::int64_t period = static_cast<std::int64_t>(
        1e9 / std::stod(ReadFile(sysfs_root() + "/trigger0/sampling_frequency")));
    std::vector<std::uint8_t> scan(size);
    for (int s = 0; s < n; ++s) {
      // One scan a period, in real time, like the hardware: never stamped ahead of now.
      std::int64_t ts = Now(mono);
      if (have_ts_ && mono == last_mono_ && last_ts_ + period > ts) {
        const std::int64_t wait = last_ts_ + period - ts;
        ::usleep(static_cast<useconds_t>(wait / 1000 + 1));
        ts = last_ts_ + period;
      }
      have_ts_ = true;
      last_mono_ = mono;
      last_ts_ = ts;
      std::fill(scan.begin(), scan.end(), 0xAB);  // padding is garbage in the kernel too
      for (std::size_t i = 0; i < els.size(); ++i) {
        const El& e = els[i];
        std::int64_t v = 0;
        if (e.channel == "in_timestamp")
          v = ts;
        else if (e.channel == "in_temp")
          v = 1234;
        else if (e.channel.rfind("in_accel_", 0) == 0)
          v = accel_raw[static_cast<std::size_t>(e.channel.back() - 'x')];
        else if (e.channel.rfind("in_anglvel_", 0) == 0)
          v = gyro_raw[static_cast<std::size_t>(e.channel.back() - 'x')];
        for (int b = 0; b < e.bytes; ++b) {
          const int shift = 8 * (e.be ? e.bytes - 1 - b : b);
          scan[offsets[i] + static_cast<std::size_t>(b)] =
              static_cast<std::uint8_t>(static_cast<std::uint64_t>(v) >> shift);
        }
      }
      if (::write(writer_, scan.data(), scan.size()) != static_cast<ssize_t>(scan.size()))
        return s;
    }
    return n;
  }

  // The device goes away: its sysfs folder and node disappear, the node's writer closes
  // (a reader sees end of file, as ENODEV from the real one).
  void Vanish() {
    vanished_ = true;
    if (writer_ >= 0)
      ::close(writer_);
    writer_ = -1;
    std::filesystem::remove_all(dir());
    std::filesystem::remove(node());
  }
  void Revive() {
    if (vanished_)
      Create();
    vanished_ = false;
  }

 private:
  static std::string ReadFile(const std::string& path) {
    std::ifstream f(path);
    std::string s;
    std::getline(f, s);
    return s;
  }
  static std::int64_t Now(bool monotonic) {
    timespec t{};
    ::clock_gettime(monotonic ? CLOCK_MONOTONIC : CLOCK_REALTIME, &t);
    return static_cast<std::int64_t>(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
  }

  void Create() {
    const std::string d = dir();
    std::filesystem::create_directories(d);
    std::filesystem::create_directories(dev_root());
    Put(d + "/name", options_.name);
    const char* axes = "xyz";
    for (int i = 0; i < 3; ++i) {
      Put(d + "/in_accel_" + axes[i] + "_raw",
          std::to_string(accel_raw[static_cast<std::size_t>(i)]));
      if (options_.gyro)
        Put(d + "/in_anglvel_" + axes[i] + "_raw",
            std::to_string(gyro_raw[static_cast<std::size_t>(i)]));
    }
    Put(d + "/in_accel_scale", "0.000598");
    if (options_.gyro)
      Put(d + "/in_anglvel_scale", "0.001000");
    Put(d + "/in_temp_raw", "1234");
    Put(d + "/in_temp_scale", "2.941176");
    Put(d + "/current_timestamp_clock", "realtime");
    if (options_.buffer) {
      std::filesystem::create_directories(d + "/scan_elements");
      std::filesystem::create_directories(d + "/buffer");
      std::filesystem::create_directories(d + "/trigger");
      // MPU-6050's layout: accel big-endian on 0..2, temp 3, gyro 4..6, timestamp 7; the
      // accel is given little-endian here so both byte orders are exercised.
      auto el = [&](const std::string& ch, int index, const char* type, bool en) {
        Put(d + "/scan_elements/" + ch + "_en", en ? "1" : "0");
        Put(d + "/scan_elements/" + ch + "_index", std::to_string(index));
        Put(d + "/scan_elements/" + ch + "_type", type);
      };
      for (int i = 0; i < 3; ++i) {
        el(std::string("in_accel_") + axes[i], i, "le:s16/16>>0", false);
        if (options_.gyro)
          el(std::string("in_anglvel_") + axes[i], 4 + i, "be:s16/16>>0", false);
      }
      el("in_temp", 3, "le:s16/16>>0", true);  // left enabled: the driver must turn it off
      el("in_timestamp", 7, "le:s64/64>>0", false);
      Put(d + "/buffer/length", "2");
      Put(d + "/buffer/enable", "0");
      Put(d + "/trigger/current_trigger", "");
      std::filesystem::create_directories(sysfs_root() + "/trigger0");
      Put(sysfs_root() + "/trigger0/name", "faketrig");
      Put(sysfs_root() + "/trigger0/sampling_frequency", "100");
      ::mkfifo(node().c_str(), 0600);
      // Held open for reading and writing: the FIFO never reports end of file to the
      // driver until Vanish() closes it (a read end alone would).
      writer_ = ::open(node().c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    }
  }

  std::string root_;
  Options options_;
  int writer_ = -1;
  bool vanished_ = false;
  bool have_ts_ = false;
  bool last_mono_ = false;
  std::int64_t last_ts_ = 0;
};

}  // namespace skyloc::drivers::testing
