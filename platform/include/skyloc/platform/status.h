// Errors as values. A Status carries a code, the errno saved at the failure site (0 if
// none) and a human-readable message in a fixed inline buffer, so building and passing
// one never allocates: the same type serves the start-up path (where messages name the
// file, key or device and the fix) and the per-frame path.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <type_traits>
#include <utility>

namespace skyloc {

enum class StatusCode : std::uint8_t {
  kOk = 0,
  kInvalidArgument,     // bad input: a config value, a file's contents, a CLI flag
  kNotFound,            // a file, device or key that does not exist
  kAlreadyExists,       // a file (a route, a recording) that would be replaced
  kOutOfRange,          // a value or index outside what is allowed
  kResourceExhausted,   // a fixed-capacity buffer is full
  kFailedPrecondition,  // called in the wrong state (not initialised, already streaming)
  kDataLoss,            // corrupt or truncated data (checksum mismatch)
  kUnavailable,         // a device that vanished or is busy; retrying may help
  kDeadlineExceeded,    // a timeout
  kPermissionDenied,    // EPERM/EACCES
  kUnimplemented,       // not built into this binary
  kInternal,            // a bug: an invariant broke
};

const char* StatusCodeName(StatusCode code);

class [[nodiscard]] Status {
 public:
  static constexpr std::size_t kMessageCapacity = 240;

  constexpr Status() = default;  // OK

  static Status Ok() { return Status(); }
  // printf-style message; it is truncated (with "...") if longer than the capacity.
  static Status Error(StatusCode code, const char* format, ...)
      __attribute__((format(printf, 2, 3)));
  // For a failed system call: pass errno saved immediately after the call. The code is
  // derived from the errno and ": <strerror>" is appended to the message.
  static Status FromErrno(int saved_errno, const char* format, ...)
      __attribute__((format(printf, 2, 3)));

  bool ok() const { return code_ == StatusCode::kOk; }
  StatusCode code() const { return code_; }
  int sys_errno() const { return sys_errno_; }
  const char* message() const { return message_; }

  // Prefixes the message with context ("loading route.db: <old message>"), so each layer
  // names what it was doing without the lower layer knowing.
  Status& AddContext(const char* format, ...) __attribute__((format(printf, 2, 3)));

 private:
  StatusCode code_ = StatusCode::kOk;
  int sys_errno_ = 0;
  char message_[kMessageCapacity] = {};
};

StatusCode StatusCodeFromErrno(int saved_errno);

// Result<T>: a T or a non-OK Status.
template <typename T>
class [[nodiscard]] Result {
 public:
  Result(const T& value) : value_(value) {}                         // NOLINT: implicit
  Result(T&& value) : value_(std::move(value)) {}                   // NOLINT: implicit
  Result(const Status& status) : status_(status) { CheckNotOk(); }  // NOLINT: implicit

  bool ok() const { return value_.has_value(); }
  const Status& status() const { return status_; }

  T& value() & { return *value_; }
  const T& value() const& { return *value_; }
  T&& value() && { return std::move(*value_); }
  T* operator->() { return &*value_; }
  const T* operator->() const { return &*value_; }
  T& operator*() & { return *value_; }
  const T& operator*() const& { return *value_; }

 private:
  void CheckNotOk() {
    // A Result built from an OK status has no value: make that a visible internal error.
    if (status_.ok())
      status_ = Status::Error(StatusCode::kInternal, "Result built from OK status");
  }

  Status status_;
  std::optional<T> value_;
};

namespace internal {
inline const Status& StatusOf(const Status& s) {
  return s;
}
template <typename T>
const Status& StatusOf(const Result<T>& r) {
  return r.status();
}
}  // namespace internal

}  // namespace skyloc

#define SKYLOC_INTERNAL_CONCAT2(a, b) a##b
#define SKYLOC_INTERNAL_CONCAT(a, b) SKYLOC_INTERNAL_CONCAT2(a, b)

// Returns the Status from the enclosing function if `expr` (a Status or Result) failed.
// The Status is copied inside the full expression: `SKYLOC_TRY(Call().AddContext(...))`
// returns a reference into a temporary, and binding that to a reference would dangle
// (AddressSanitizer found it through the route-database fuzz target).
#define SKYLOC_TRY(expr)                                                                \
  do {                                                                                  \
    if (const ::skyloc::Status skyloc_try_status_ = ::skyloc::internal::StatusOf(expr); \
        !skyloc_try_status_.ok()) {                                                     \
      return skyloc_try_status_;                                                        \
    }                                                                                   \
  } while (false)

// Declares or assigns `lhs` from a Result, or returns its Status on failure:
//   SKYLOC_TRY_ASSIGN(auto file, OpenFile(path));
#define SKYLOC_TRY_ASSIGN(lhs, expr) \
  SKYLOC_INTERNAL_TRY_ASSIGN(SKYLOC_INTERNAL_CONCAT(skyloc_try_r_, __LINE__), lhs, expr)
#define SKYLOC_INTERNAL_TRY_ASSIGN(tmp, lhs, expr) \
  auto tmp = (expr);                               \
  if (!tmp.ok())                                   \
    return tmp.status();                           \
  lhs = std::move(tmp).value()
