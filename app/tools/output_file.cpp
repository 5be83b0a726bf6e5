#include "tools/output_file.h"

#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdarg>

namespace skyloc::tools {

Status OutFile::Open(const std::string& path) {
  path_ = path;
  const std::size_t slash = path.rfind('/');
  const std::size_t name_at = slash == std::string::npos ? 0 : slash + 1;
  tmp_ = path.substr(0, name_at) + "." + path.substr(name_at) + ".tmp.XXXXXX";
  const int fd = ::mkstemp(tmp_.data());
  if (fd < 0) {
    const int saved = errno;
    tmp_.clear();
    return Status::FromErrno(saved, "cannot create a temporary file for %s", path.c_str());
  }
  ::fchmod(fd, 0644);  // mkstemp's 0600 is not what a result file needs
  f_ = ::fdopen(fd, "w");
  if (f_ == nullptr) {
    const int saved = errno;
    ::close(fd);
    Discard();
    return Status::FromErrno(saved, "cannot open %s", tmp_.c_str());
  }
  return Status::Ok();
}

Status OutFile::Close() {
  int saved = 0;
  // Every step, errno saved at once; the first failure is the one reported.
  if (std::ferror(f_) != 0)
    saved = errno != 0 ? errno : EIO;
  if (saved == 0 && std::fflush(f_) != 0)
    saved = errno;
  if (saved == 0 && ::fsync(::fileno(f_)) != 0)
    saved = errno;
  const int closed = std::fclose(f_);
  if (saved == 0 && closed != 0)
    saved = errno;
  f_ = nullptr;
  if (saved != 0) {
    Discard();
    return Status::FromErrno(saved, "cannot write %s (the previous file, if any, is kept)",
                             path_.c_str());
  }
  if (::rename(tmp_.c_str(), path_.c_str()) != 0) {
    saved = errno;
    Discard();
    return Status::FromErrno(saved, "cannot rename the new %s into place", path_.c_str());
  }
  tmp_.clear();
  return Status::Ok();
}

OutFile::~OutFile() {
  if (f_ != nullptr)
    std::fclose(f_);
  Discard();
}

void OutFile::Discard() {
  if (!tmp_.empty())
    ::unlink(tmp_.c_str());
  tmp_.clear();
}

Status WriteText(const std::string& path, const std::string& text) {
  OutFile f;
  SKYLOC_TRY(f.Open(path));
  if (std::fwrite(text.data(), 1, text.size(), f.get()) != text.size()) {
    const int saved = errno;
    (void)f.Close();  // discards the temporary file
    return Status::FromErrno(saved, "cannot write %s (the previous file, if any, is kept)",
                             path.c_str());
  }
  return f.Close();
}

std::string Format(const char* format, ...) {
  char buffer[1024];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return buffer;
}

}  // namespace skyloc::tools
