// Owns one mmap()ed region (a V4L2 capture buffer, a libcamera dmabuf plane): unmapped
// exactly once, move-only, like UniqueFd for memory.
#pragma once

#include <sys/types.h>

#include <cstddef>
#include <cstdint>

#include "skyloc/platform/status.h"

namespace skyloc::drivers {

class MappedBuffer final {
 public:
  MappedBuffer() = default;
  MappedBuffer(MappedBuffer&& other) noexcept;
  MappedBuffer& operator=(MappedBuffer&& other) noexcept;
  MappedBuffer(const MappedBuffer&) = delete;
  MappedBuffer& operator=(const MappedBuffer&) = delete;
  ~MappedBuffer() { Unmap(); }

  // Maps `length` bytes of `fd` at `offset`, read-only and shared (the device writes,
  // we read). Replaces any earlier mapping.
  Status Map(int fd, off_t offset, std::size_t length);
  void Unmap();

  const std::uint8_t* data() const { return data_; }
  std::size_t size() const { return length_; }
  bool is_mapped() const { return data_ != nullptr; }

 private:
  const std::uint8_t* data_ = nullptr;
  std::size_t length_ = 0;
};

}  // namespace skyloc::drivers
