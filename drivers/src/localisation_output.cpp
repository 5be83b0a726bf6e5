#include "skyloc/drivers/localisation_output.h"

#include <new>

namespace skyloc::drivers {

void FileLinesOutput::Publish(const LocalisationMessage& m) {
  ++counters_.published;
  // One line per frame must reach a pipe's reader promptly: flushed at once.
  const std::size_t n = std::size_t{m.json_length} + m.devices_length;
  if (std::fwrite(m.json, 1, n, out_) != n || std::fflush(out_) != 0)
    ++counters_.dropped;
}

Status MemoryOutput::Open() {
  messages_.reset(new (std::nothrow) LocalisationMessage[capacity_]);
  if (messages_ == nullptr)
    return Status::Error(StatusCode::kResourceExhausted,
                         "memory output: cannot allocate %zu messages", capacity_);
  size_ = 0;
  return Status::Ok();
}

void MemoryOutput::Publish(const LocalisationMessage& m) {
  ++counters_.published;
  if (size_ < capacity_)
    messages_[size_++] = m;
  else
    ++counters_.dropped;
}

}  // namespace skyloc::drivers
