// An array whose size is chosen at start-up (from the configuration) and never changes.
// Allocate() is the only allocation; a failure is a Status, not an exception.
#pragma once

#include <cstddef>
#include <limits>
#include <memory>
#include <new>
#include <span>

#include "skyloc/platform/status.h"

namespace skyloc {

template <typename T>
class FixedArray {
 public:
  FixedArray() = default;
  FixedArray(FixedArray&&) noexcept = default;
  FixedArray& operator=(FixedArray&&) noexcept = default;
  FixedArray(const FixedArray&) = delete;
  FixedArray& operator=(const FixedArray&) = delete;

  // Allocates `count` value-initialised elements. Calling it again replaces the storage;
  // that is start-up work only.
  Status Allocate(std::size_t count) {
    // A count whose byte size overflows makes even a nothrow new[] throw
    // std::bad_array_new_length (GCC), so it is refused before new is reached; no object
    // may exceed PTRDIFF_MAX bytes anyway.
    const bool too_large =
        count > static_cast<std::size_t>(std::numeric_limits<std::ptrdiff_t>::max()) / sizeof(T);
    data_.reset(too_large ? nullptr : new (std::nothrow) T[count == 0 ? 1 : count]());
    if (!data_) {
      size_ = 0;
      return Status::Error(StatusCode::kResourceExhausted,
                           "cannot allocate %zu elements of %zu bytes: lower the capacity in "
                           "the configuration",
                           count, sizeof(T));
    }
    size_ = count;
    return Status::Ok();
  }

  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  T* data() { return data_.get(); }
  const T* data() const { return data_.get(); }
  T& operator[](std::size_t i) { return data_[i]; }
  const T& operator[](std::size_t i) const { return data_[i]; }
  std::span<T> span() { return {data_.get(), size_}; }
  std::span<const T> span() const { return {data_.get(), size_}; }
  T* begin() { return data_.get(); }
  T* end() { return data_.get() + size_; }
  const T* begin() const { return data_.get(); }
  const T* end() const { return data_.get() + size_; }

 private:
  std::unique_ptr<T[]> data_;
  std::size_t size_ = 0;
};

}  // namespace skyloc
