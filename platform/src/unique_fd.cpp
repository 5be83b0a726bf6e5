#include "skyloc/platform/unique_fd.h"

#include <unistd.h>

namespace skyloc {

void UniqueFd::reset(int fd) {
  if (fd_ >= 0 && fd_ != fd) {
    // close() is not retried on EINTR: on Linux the descriptor is released regardless.
    ::close(fd_);
  }
  fd_ = fd;
}

}  // namespace skyloc
