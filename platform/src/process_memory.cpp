#include "skyloc/platform/process_memory.h"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstdlib>

#include "skyloc/platform/unique_fd.h"

namespace skyloc {

Result<std::size_t> ResidentSetBytes() {
  UniqueFd fd(::open("/proc/self/statm", O_RDONLY | O_CLOEXEC));
  if (!fd.is_valid())
    return Status::FromErrno(errno, "cannot open /proc/self/statm");
  char text[128];
  ssize_t n;
  do {
    n = ::read(fd.get(), text, sizeof text - 1);
  } while (n < 0 && errno == EINTR);
  if (n <= 0)
    return Status::FromErrno(n < 0 ? errno : EIO, "cannot read /proc/self/statm");
  text[n] = '\0';
  // "size resident shared text lib data dt", in pages.
  char* end = nullptr;
  std::strtoull(text, &end, 10);
  const unsigned long long pages = std::strtoull(end, &end, 10);
  const long page = ::sysconf(_SC_PAGESIZE);
  return static_cast<std::size_t>(pages) * static_cast<std::size_t>(page > 0 ? page : 4096);
}

}  // namespace skyloc
