// The system calls the V4L2 driver makes (open, ioctl, poll) and its time (now, sleep),
// behind one interface, so a test can put a scripted device and a manual clock under the
// real driver code and drive unplugs, stalls, drops and corrupt frames without hardware.
// Descriptors returned by Open() must be real (closed with close(), mapped with mmap()):
// the fake device in the tests uses a memfd.
#pragma once

#include "skyloc/platform/clock.h"

namespace skyloc::drivers {

class V4l2Io {
 public:
  virtual ~V4l2Io() = default;
  // Like open(2)/ioctl(2): -1 and errno on failure.
  virtual int Open(const char* path, int flags) = 0;
  virtual int Ioctl(int fd, unsigned long request, void* arg) = 0;
  // poll(2) for POLLIN on one descriptor: 1 ready (or an error to collect), 0 timeout,
  // -1 and errno.
  virtual int Poll(int fd, int timeout_ms) = 0;
  virtual Nanoseconds Now() = 0;  // CLOCK_MONOTONIC, the clock of V4L2 timestamps
  virtual void SleepFor(Nanoseconds duration) = 0;

 protected:
  V4l2Io() = default;
  V4l2Io(const V4l2Io&) = default;
  V4l2Io& operator=(const V4l2Io&) = default;
};

// The real system calls.
V4l2Io& SystemV4l2Io();

}  // namespace skyloc::drivers
