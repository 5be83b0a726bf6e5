// Whether this test program runs under a user-mode emulator (qemu-user), as the cross
// builds' tests do under ctest. qemu-user 7.2 on the build machines spins in a forked
// child that changes its user id or writes past RLIMIT_FSIZE, so tests that need setresuid
// or a file-size limit in a child skip there; they run natively in the arm64 VM
// (tests/hil), where the parent is an arm64 shell. (Threads run under it: the recorder's
// writer, the output publisher and the queue's two-thread test do.)
#pragma once

#include <fcntl.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>

namespace skyloc::testing {

// The ELF machine (e_machine) of an executable, or 0 when it cannot be read.
inline std::uint16_t ElfMachine(const char* path) {
  const int fd = ::open(path, O_RDONLY | O_CLOEXEC);
  if (fd < 0)
    return 0;
  unsigned char header[20] = {};
  const bool ok = ::read(fd, header, sizeof header) == static_cast<ssize_t>(sizeof header);
  ::close(fd);
  if (!ok || header[0] != 0x7f || header[1] != 'E')
    return 0;
  return static_cast<std::uint16_t>(header[18] | (header[19] << 8));  // little-endian targets
}

// True when this program is built for another machine than its parent process (ctest, a
// shell) runs on: the emulator is the only way that can happen.
inline bool UnderUserModeEmulator() {
  char parent[64];
  std::snprintf(parent, sizeof parent, "/proc/%d/exe", static_cast<int>(::getppid()));
  const std::uint16_t self = ElfMachine("/proc/self/exe");
  const std::uint16_t host = ElfMachine(parent);
  return self != 0 && host != 0 && self != host;
}

}  // namespace skyloc::testing
