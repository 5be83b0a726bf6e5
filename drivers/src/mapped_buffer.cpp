#include "skyloc/drivers/mapped_buffer.h"

#include <sys/mman.h>

#include <cerrno>
#include <utility>

namespace skyloc::drivers {

MappedBuffer::MappedBuffer(MappedBuffer&& other) noexcept
    : data_(std::exchange(other.data_, nullptr)), length_(std::exchange(other.length_, 0)) {}

MappedBuffer& MappedBuffer::operator=(MappedBuffer&& other) noexcept {
  if (this != &other) {
    Unmap();
    data_ = std::exchange(other.data_, nullptr);
    length_ = std::exchange(other.length_, 0);
  }
  return *this;
}

Status MappedBuffer::Map(int fd, off_t offset, std::size_t length) {
  Unmap();
  void* p = ::mmap(nullptr, length, PROT_READ, MAP_SHARED, fd, offset);
  if (p == MAP_FAILED) {
    const int saved = errno;
    return Status::FromErrno(saved, "mmap of %zu bytes at offset %lld failed", length,
                             static_cast<long long>(offset));
  }
  data_ = static_cast<const std::uint8_t*>(p);
  length_ = length;
  return Status::Ok();
}

void MappedBuffer::Unmap() {
  if (data_ != nullptr) {
    // const_cast: munmap takes void*; the mapping is read-only and never written by us.
    ::munmap(const_cast<std::uint8_t*>(data_), length_);
    data_ = nullptr;
    length_ = 0;
  }
}

}  // namespace skyloc::drivers
