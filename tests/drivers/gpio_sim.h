// The pins of a gpio-sim chip, seen from the simulator's side through sysfs
// (<chip dir>/sim_gpio<offset>/{value,pull}): what the kernel really drives on a line, and
// a way to pull an input line like a button would. Independent of libgpiod, so the GPIO
// driver's output is checked by something other than itself.
#pragma once

#include <fcntl.h>
#include <glob.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <string>

#include "skyloc/platform/status.h"
#include "test_env.h"

namespace skyloc::drivers::testing {

class GpioSimPins {
 public:
  // SKYLOC_TEST_GPIO_SIM_DIR if set, else /sys/devices/platform/gpio-sim.*/<chip_name>.
  static Result<GpioSimPins> Find(const char* chip_name) {
    GpioSimPins pins;
    if (const char* env = Env("SKYLOC_TEST_GPIO_SIM_DIR")) {
      pins.dir_ = env;
      return pins;
    }
    if (chip_name == nullptr || chip_name[0] == '\0') {
      return Status::Error(StatusCode::kFailedPrecondition,
                           "gpio-sim read-back needs the chip's name (open it first) or "
                           "SKYLOC_TEST_GPIO_SIM_DIR");
    }
    const std::string pattern = std::string("/sys/devices/platform/gpio-sim.*/") + chip_name;
    glob_t g{};
    if (::glob(pattern.c_str(), 0, nullptr, &g) == 0 && g.gl_pathc > 0)
      pins.dir_ = g.gl_pathv[0];
    ::globfree(&g);
    if (pins.dir_.empty()) {
      return Status::Error(StatusCode::kNotFound,
                           "%s is not a gpio-sim chip (no %s): set SKYLOC_TEST_GPIO_SIM_DIR",
                           chip_name, pattern.c_str());
    }
    return pins;
  }

  // The level the line is driven to (or pulled to, when nobody drives it).
  Result<bool> Level(unsigned offset) const {
    const std::string path = File(offset, "value");
    const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "reading back %s", path.c_str());
    }
    char c = 0;
    const ssize_t n = ::read(fd, &c, 1);
    ::close(fd);
    if (n != 1)
      return Status::Error(StatusCode::kDataLoss, "%s is empty", path.c_str());
    return c == '1';
  }

  // Pulls the simulated pin up or down: what a button does to an input line.
  Status Pull(unsigned offset, bool up) const {
    const std::string path = File(offset, "pull");
    const int fd = ::open(path.c_str(), O_WRONLY | O_CLOEXEC);
    if (fd < 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "opening %s", path.c_str());
    }
    const char* text = up ? "pull-up" : "pull-down";
    const ssize_t n = ::write(fd, text, std::strlen(text));
    const int saved = errno;
    ::close(fd);
    if (n < 0)
      return Status::FromErrno(saved, "writing %s to %s", text, path.c_str());
    return Status::Ok();
  }

  const std::string& dir() const { return dir_; }

 private:
  std::string File(unsigned offset, const char* name) const {
    return dir_ + "/sim_gpio" + std::to_string(offset) + "/" + name;
  }

  std::string dir_;
};

}  // namespace skyloc::drivers::testing
