#include "skyloc/platform/status.h"

#include <cerrno>
#include <cstdarg>
#include <cstdio>
#include <cstring>

namespace skyloc {
namespace {

// The attribute tells clang the va_list carries printf arguments (else -Wformat-nonliteral).
__attribute__((format(printf, 3, 0))) void FormatInto(char* buffer, std::size_t capacity,
                                                      const char* format, std::va_list args) {
  const int written = std::vsnprintf(buffer, capacity, format, args);
  if (written >= 0 && static_cast<std::size_t>(written) >= capacity && capacity > 4) {
    std::memcpy(buffer + capacity - 4, "...", 4);
  }
}

// out = a + ": " + b, truncated to capacity with a trailing "..." when it does not fit.
void JoinInto(char* out, std::size_t capacity, const char* a, const char* b) {
  std::size_t n = 0;
  bool truncated = false;
  for (const char* part : {a, ": ", b}) {
    for (const char* c = part; *c != '\0'; ++c) {
      if (n + 1 >= capacity) {
        truncated = true;
        break;
      }
      out[n++] = *c;
    }
  }
  out[n] = '\0';
  if (truncated && capacity > 4)
    std::memcpy(out + capacity - 4, "...", 4);
}

}  // namespace

const char* StatusCodeName(StatusCode code) {
  switch (code) {
    case StatusCode::kOk:
      return "OK";
    case StatusCode::kInvalidArgument:
      return "INVALID_ARGUMENT";
    case StatusCode::kNotFound:
      return "NOT_FOUND";
    case StatusCode::kOutOfRange:
      return "OUT_OF_RANGE";
    case StatusCode::kResourceExhausted:
      return "RESOURCE_EXHAUSTED";
    case StatusCode::kFailedPrecondition:
      return "FAILED_PRECONDITION";
    case StatusCode::kDataLoss:
      return "DATA_LOSS";
    case StatusCode::kUnavailable:
      return "UNAVAILABLE";
    case StatusCode::kDeadlineExceeded:
      return "DEADLINE_EXCEEDED";
    case StatusCode::kPermissionDenied:
      return "PERMISSION_DENIED";
    case StatusCode::kUnimplemented:
      return "UNIMPLEMENTED";
    case StatusCode::kAlreadyExists:
      return "ALREADY_EXISTS";
    case StatusCode::kInternal:
      return "INTERNAL";
  }
  return "UNKNOWN";
}

StatusCode StatusCodeFromErrno(int saved_errno) {
  switch (saved_errno) {
    case 0:
      return StatusCode::kOk;
    case ENOENT:
      return StatusCode::kNotFound;
    case EEXIST:
      return StatusCode::kAlreadyExists;
    case EACCES:
    case EPERM:
      return StatusCode::kPermissionDenied;
    case EINVAL:
      return StatusCode::kInvalidArgument;
    case ERANGE:
    case EOVERFLOW:
      return StatusCode::kOutOfRange;
    case ENOMEM:
    case ENOSPC:
      return StatusCode::kResourceExhausted;
    case ETIMEDOUT:
      return StatusCode::kDeadlineExceeded;
    case ENODEV:
    case ENXIO:
    case EIO:
    case EBUSY:
    case EAGAIN:
    case EINTR:
      return StatusCode::kUnavailable;
    case ENOTTY:
    case ENOSYS:
    case EOPNOTSUPP:
      return StatusCode::kUnimplemented;
    default:
      return StatusCode::kInternal;
  }
}

Status Status::Error(StatusCode code, const char* format, ...) {
  Status s;
  s.code_ = code == StatusCode::kOk ? StatusCode::kInternal : code;
  std::va_list args;
  va_start(args, format);
  FormatInto(s.message_, kMessageCapacity, format, args);
  va_end(args);
  return s;
}

Status Status::FromErrno(int saved_errno, const char* format, ...) {
  Status s;
  s.sys_errno_ = saved_errno;
  s.code_ = saved_errno == 0 ? StatusCode::kInternal : StatusCodeFromErrno(saved_errno);
  char head[kMessageCapacity];
  std::va_list args;
  va_start(args, format);
  FormatInto(head, sizeof head, format, args);
  va_end(args);
  // strerrordesc_np is async-signal-safe and thread-safe, unlike strerror.
  const char* text = strerrordesc_np(saved_errno);
  JoinInto(s.message_, kMessageCapacity, head, text ? text : "unknown error");
  return s;
}

Status& Status::AddContext(const char* format, ...) {
  char head[kMessageCapacity];
  std::va_list args;
  va_start(args, format);
  FormatInto(head, sizeof head, format, args);
  va_end(args);
  char old[kMessageCapacity];
  std::memcpy(old, message_, kMessageCapacity);
  JoinInto(message_, kMessageCapacity, head, old);
  return *this;
}

}  // namespace skyloc
