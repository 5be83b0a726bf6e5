// Test helper: a status output that only remembers what it was told (the state shown
// last, how often it changed, whether the lines are in the safe state), so frame-loop
// tests can check the shutdown and fault paths in one line. The product's simulated
// output is drivers::SimulatedStatusOutput.
#pragma once

#include <cstdint>

#include "skyloc/drivers/status_output.h"

namespace skyloc::app {

class RecordingStatusOutput final : public drivers::StatusOutput {
 public:
  Status Open() override {
    open_ = true;
    return SafeState();
  }
  Status Show(drivers::LocalisationState state, float confidence, Nanoseconds now) override {
    if (!open_)
      return Status::Error(StatusCode::kFailedPrecondition, "status output is not open");
    if (safe_ || state != last_)
      ++changes_;
    last_ = state;
    confidence_ = confidence;
    last_time_ = now;
    safe_ = false;
    return Status::Ok();
  }
  Status SafeState() override {
    safe_ = true;
    return Status::Ok();
  }
  void Close() override {
    (void)SafeState();
    open_ = false;
  }

  bool is_safe() const { return safe_; }
  bool is_open() const { return open_; }
  drivers::LocalisationState last_state() const { return last_; }
  float last_confidence() const { return confidence_; }
  std::uint64_t changes() const { return changes_; }

 private:
  bool open_ = false;
  bool safe_ = true;
  drivers::LocalisationState last_ = drivers::LocalisationState::kLost;
  float confidence_ = 0;
  Nanoseconds last_time_{0};
  std::uint64_t changes_ = 0;
};

}  // namespace skyloc::app
