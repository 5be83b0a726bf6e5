#include <fcntl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "skyloc/drivers/localisation_output.h"

namespace skyloc::drivers {

UnixSocketOutput::UnixSocketOutput(const UnixSocketOutputConfig& config) : config_(config) {
  std::snprintf(name_, sizeof name_, "socket %s", config_.path);
  for (int& fd : readers_)
    fd = -1;
}

UnixSocketOutput::~UnixSocketOutput() {
  Close();
}

Status UnixSocketOutput::Open() {
  if (listen_fd_ >= 0)
    return Status::Error(StatusCode::kFailedPrecondition, "%s is already open", name_);
  if (config_.max_readers < 1 || config_.max_readers > kMaxReaders)
    return Status::Error(StatusCode::kInvalidArgument, "%s: max_readers %d is not 1..%d", name_,
                         config_.max_readers, kMaxReaders);
  const std::size_t length = std::strlen(config_.path);
  sockaddr_un address{};
  if (length == 0 || length >= sizeof address.sun_path)
    return Status::Error(StatusCode::kInvalidArgument, "%s: the path must be 1..%zu characters",
                         name_, sizeof address.sun_path - 1);
  address.sun_family = AF_UNIX;
  std::memcpy(address.sun_path, config_.path, length);
  // A socket file left by a run that crashed would make bind() fail: replace it, but
  // never anything that is not a socket.
  struct stat st {};
  if (::lstat(config_.path, &st) == 0) {
    if (!S_ISSOCK(st.st_mode))
      return Status::Error(StatusCode::kAlreadyExists,
                           "%s: the path exists and is not a socket: remove it or set [output] "
                           "socket_path to another path",
                           name_);
    if (::unlink(config_.path) != 0)
      return Status::FromErrno(errno, "%s: cannot remove the old socket file", name_);
  }
  const int fd = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0)
    return Status::FromErrno(errno, "%s: socket()", name_);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) != 0) {
    const int e = errno;
    ::close(fd);
    return Status::FromErrno(e,
                             "%s: cannot create the socket (does its folder exist and may skyloc "
                             "write there? the systemd unit makes /run/skyloc)",
                             name_);
  }
  if (::chmod(config_.path, config_.mode) != 0 || ::listen(fd, config_.max_readers) != 0) {
    const int e = errno;
    ::close(fd);
    ::unlink(config_.path);
    return Status::FromErrno(e, "%s: chmod/listen", name_);
  }
  listen_fd_ = fd;
  return Status::Ok();
}

void UnixSocketOutput::AcceptReaders() {
  for (;;) {
    const int fd = ::accept4(listen_fd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0)
      return;  // EAGAIN: nobody waiting; anything else is retried at the next frame
    int* free_slot = nullptr;
    for (int i = 0; i < config_.max_readers && free_slot == nullptr; ++i)
      if (readers_[i] < 0)
        free_slot = &readers_[i];
    if (free_slot == nullptr) {
      ::close(fd);
      ++counters_.readers_refused;
      continue;
    }
    *free_slot = fd;
    ++counters_.readers_seen;
  }
}

void UnixSocketOutput::Publish(const LocalisationMessage& m) {
  if (listen_fd_ < 0)
    return;
  ++counters_.published;
  AcceptReaders();
  for (int i = 0; i < config_.max_readers; ++i) {
    const int fd = readers_[i];
    if (fd < 0)
      continue;
    ssize_t sent = ::send(fd, m.json, m.json_length, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (sent >= 0 && m.devices_length > 0)
      sent = ::send(fd, m.json + m.json_length, m.devices_length, MSG_DONTWAIT | MSG_NOSIGNAL);
    if (sent >= 0)
      continue;
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS) {
      ++counters_.dropped;  // this reader is not keeping up: it misses this frame
    } else {
      ::close(fd);  // EPIPE, ECONNRESET: the reader went away
      readers_[i] = -1;
      ++counters_.readers_gone;
    }
  }
}

int UnixSocketOutput::readers() const {
  int n = 0;
  for (const int fd : readers_)
    n += fd >= 0 ? 1 : 0;
  return n;
}

void UnixSocketOutput::Close() {
  for (int& fd : readers_) {
    if (fd >= 0)
      ::close(fd);
    fd = -1;
  }
  if (listen_fd_ >= 0) {
    ::close(listen_fd_);
    ::unlink(config_.path);
    listen_fd_ = -1;
  }
}

}  // namespace skyloc::drivers
