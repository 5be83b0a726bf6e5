// The route's lock, FILE.db.lock: an OFD lock taken before a teach touches the route or
// its FILE.db.tmp, so two teaches never write one route (docs/ROUTE_DB.md).
#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>

#include "firmware/route_db.h"
#include "skyloc/platform/regular_file.h"

namespace skyloc::firmware {

namespace {

// A whole-file OFD lock request of `type` (F_WRLCK, F_UNLCK).
struct flock WholeFile(short type) {
  struct flock fl {};
  fl.l_type = type;
  fl.l_whence = SEEK_SET;
  fl.l_start = 0;
  fl.l_len = 0;
  return fl;
}

// The process id the lock's holder wrote into it; 0 when unreadable.
long HolderPid(int fd) {
  char text[24] = {};
  const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
  if (n <= 0)
    return 0;
  return std::strtol(text, nullptr, 10);
}

// FILE.db.lock, the lock of the route at ROUTE_PATH; false when it does not fit.
template <std::size_t N>
bool LockPathOf(const char* route_path, char (&out)[N]) {
  return std::snprintf(out, N, "%s.lock", route_path) < static_cast<int>(N);
}

}  // namespace

Status RouteLock::Acquire(const char* route_path) {
  Release();
  char lock_path[sizeof path_];
  if (!LockPathOf(route_path, lock_path))
    return Status::Error(StatusCode::kInvalidArgument, "path too long: %s", route_path);
  // The holder removes the file while it holds the lock; a lock taken on a file that was
  // removed (or replaced) meanwhile excludes nobody, so it is let go and taken again.
  for (int attempt = 0; attempt < 100; ++attempt) {
    UniqueFd fd;
    SKYLOC_TRY(CreateRegularFile(lock_path, O_RDWR, 0644, "the route's lock file",
                                 "remove it so a teach can lock the route", &fd));
    struct stat opened {};
    if (::fstat(fd.get(), &opened) != 0)
      return Status::FromErrno(errno, "cannot stat %s", lock_path);
    struct flock fl = WholeFile(F_WRLCK);
    if (::fcntl(fd.get(), F_OFD_SETLK, &fl) != 0) {
      const int e = errno;
      if (e != EAGAIN && e != EACCES)
        return Status::FromErrno(e, "cannot lock %s", lock_path);
      const long pid = HolderPid(fd.get());
      return Status::Error(StatusCode::kUnavailable,
                           "route %s is being taught by process %ld (it holds %s): wait for that "
                           "teach to end (SIGINT commits it); two teaches never write one route",
                           route_path, pid, lock_path);
    }
    struct stat now {};
    if (::lstat(lock_path, &now) != 0 || now.st_ino != opened.st_ino || now.st_dev != opened.st_dev)
      continue;
    char pid[24];
    const int n = std::snprintf(pid, sizeof pid, "%ld\n", static_cast<long>(::getpid()));
    if (::ftruncate(fd.get(), 0) != 0 ||
        ::pwrite(fd.get(), pid, static_cast<std::size_t>(n), 0) != n)
      return Status::FromErrno(errno, "cannot write %s", lock_path);
    fd_ = std::move(fd);
    std::snprintf(path_, sizeof path_, "%s", lock_path);
    return Status::Ok();
  }
  return Status::Error(StatusCode::kUnavailable,
                       "cannot take the lock %s: it is removed and made again as fast as it is "
                       "taken; is something else teaching %s?",
                       lock_path, route_path);
}

void RouteLock::Release() {
  if (!fd_.is_valid())
    return;
  // Removed while still held: whoever opened it meanwhile finds it gone once it gets the
  // lock, and takes the lock on a new file (Acquire).
  (void)::unlink(path_);
  fd_.reset();
}

bool RouteBeingTaught(const char* route_path, long* pid) {
  *pid = 0;
  char lock_path[RouteLock::kPathCapacity];
  if (!LockPathOf(route_path, lock_path))
    return false;
  UniqueFd fd(::open(lock_path, O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC));
  if (!fd.is_valid())
    return false;
  struct flock fl = WholeFile(F_WRLCK);
  if (::fcntl(fd.get(), F_OFD_GETLK, &fl) != 0 || fl.l_type == F_UNLCK)
    return false;
  *pid = HolderPid(fd.get());
  return true;
}

}  // namespace skyloc::firmware
