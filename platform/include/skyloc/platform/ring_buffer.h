// Fixed-capacity FIFO over storage the caller owns. It never grows: a push onto a full
// buffer either fails (TryPush) or replaces the oldest element and counts it (PushOverwrite),
// so the owner always knows that data was lost.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace skyloc {

// The index arithmetic of a ring, separate from the storage so that 2-D rings (rows of
// a matrix whose width is only known at start-up) reuse it.
class RingIndex {
 public:
  RingIndex() = default;
  explicit RingIndex(std::size_t capacity) : capacity_(capacity) {}

  std::size_t capacity() const { return capacity_; }
  std::size_t size() const { return size_; }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == capacity_; }
  // Elements replaced by PushOverwrite since construction or Clear().
  std::uint64_t overwritten() const { return overwritten_; }

  // Slot of the i-th element, 0 = oldest. Precondition: i < size().
  std::size_t Slot(std::size_t i) const { return Wrap(head_ + i); }
  // Slot of the i-th newest element, 0 = newest. Precondition: i < size().
  std::size_t SlotFromNewest(std::size_t i) const { return Wrap(head_ + size_ - 1 - i); }

  // Reserves the slot for a new element; false (nothing changes) if full or capacity 0.
  [[nodiscard]] bool TryPushSlot(std::size_t* slot) {
    if (full() || capacity_ == 0)
      return false;
    *slot = Wrap(head_ + size_);
    ++size_;
    return true;
  }
  // Reserves the slot for a new element, dropping the oldest if full. Returns the slot.
  // Precondition: capacity() > 0.
  std::size_t PushOverwriteSlot() {
    if (full()) {
      head_ = Wrap(head_ + 1);
      --size_;
      ++overwritten_;
    }
    const std::size_t slot = Wrap(head_ + size_);
    ++size_;
    return slot;
  }
  // Drops the oldest element; false if empty.
  bool PopOldest() {
    if (empty())
      return false;
    head_ = Wrap(head_ + 1);
    --size_;
    return true;
  }
  void Clear() {
    head_ = 0;
    size_ = 0;
    overwritten_ = 0;
  }

 private:
  std::size_t Wrap(std::size_t i) const { return i >= capacity_ ? i - capacity_ : i; }

  std::size_t capacity_ = 0;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  std::uint64_t overwritten_ = 0;
};

template <typename T>
class RingBuffer {
 public:
  RingBuffer() = default;
  explicit RingBuffer(std::span<T> storage) { SetStorage(storage); }
  // Points the ring at new storage and empties it.
  void SetStorage(std::span<T> storage) {
    storage_ = storage;
    index_ = RingIndex(storage.size());
  }

  std::size_t capacity() const { return index_.capacity(); }
  std::size_t size() const { return index_.size(); }
  bool empty() const { return index_.empty(); }
  bool full() const { return index_.full(); }
  std::uint64_t overwritten() const { return index_.overwritten(); }

  [[nodiscard]] bool TryPush(const T& value) {
    std::size_t slot = 0;
    if (!index_.TryPushSlot(&slot))
      return false;
    storage_[slot] = value;
    return true;
  }
  // Returns true if the oldest element was replaced to make room. Capacity must be > 0.
  bool PushOverwrite(const T& value) {
    const bool was_full = index_.full();
    storage_[index_.PushOverwriteSlot()] = value;
    return was_full;
  }
  bool PopOldest() { return index_.PopOldest(); }
  void Clear() { index_.Clear(); }

  // 0 = oldest.
  T& operator[](std::size_t i) { return storage_[index_.Slot(i)]; }
  const T& operator[](std::size_t i) const { return storage_[index_.Slot(i)]; }
  // 0 = newest.
  T& FromNewest(std::size_t i) { return storage_[index_.SlotFromNewest(i)]; }
  const T& FromNewest(std::size_t i) const { return storage_[index_.SlotFromNewest(i)]; }

 private:
  std::span<T> storage_;
  RingIndex index_;
};

}  // namespace skyloc
