#include "skyloc/platform/regular_file.h"

#include <fcntl.h>
#include <sys/stat.h>

#include <cerrno>
#include <utility>

namespace skyloc {

const char* FileKindName(mode_t mode) {
  if (S_ISFIFO(mode))
    return "a FIFO";
  if (S_ISCHR(mode) || S_ISBLK(mode))
    return "a device node";
  if (S_ISDIR(mode))
    return "a directory";
  if (S_ISLNK(mode))
    return "a symbolic link";
  if (S_ISSOCK(mode))
    return "a socket";
  return "not a regular file";
}

namespace {

// `fd`, opened non-blocking at `path`, into `*out` when it is a regular file (switched back
// to blocking); else the error that says what it is and `fix`.
Status KeepRegularFile(UniqueFd fd, const char* path, const char* what, const char* fix,
                       UniqueFd* out) {
  struct stat st {};
  if (::fstat(fd.get(), &st) != 0)
    return Status::FromErrno(errno, "cannot stat %s %s", what, path);
  if (!S_ISREG(st.st_mode))
    return Status::Error(StatusCode::kInvalidArgument, "%s %s is %s, not a regular file: %s", what,
                         path, FileKindName(st.st_mode), fix);
  const int fl = ::fcntl(fd.get(), F_GETFL);
  if (fl < 0 || ::fcntl(fd.get(), F_SETFL, fl & ~O_NONBLOCK) != 0)
    return Status::FromErrno(errno, "cannot set %s %s to blocking I/O", what, path);
  *out = std::move(fd);
  return Status::Ok();
}

}  // namespace

Status OpenRegularFile(const char* path, int flags, const char* what, UniqueFd* out) {
  UniqueFd fd(::open(path, flags | O_NONBLOCK | O_CLOEXEC));
  if (!fd.is_valid())
    return Status::FromErrno(errno, "cannot open %s %s", what, path);
  return KeepRegularFile(std::move(fd), path, what, "name a regular file", out);
}

Status CreateRegularFile(const char* path, int flags, mode_t mode, const char* what,
                         const char* fix, UniqueFd* out) {
  UniqueFd fd(::open(path, flags | O_CREAT | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC, mode));
  if (!fd.is_valid())
    return Status::FromErrno(errno, "cannot create %s %s", what, path);
  return KeepRegularFile(std::move(fd), path, what, fix, out);
}

}  // namespace skyloc
