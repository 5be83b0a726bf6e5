// Test helper: a status output (one line per state) that only remembers what it was told
// (the state shown last, how often the lines changed, whether they are in the safe state),
// so frame-loop tests can check the shutdown and fault paths in one line. The product's
// simulated output is drivers::SimulatedStatusOutput.
#pragma once

#include <cstdint>

#include "skyloc/drivers/status_output.h"

namespace skyloc::app {

class RecordingStatusOutput final : public drivers::StatusOutput {
 public:
  RecordingStatusOutput()
      : StatusOutput(drivers::StatusLineMode::kLinePerState, "recording status output") {}
  ~RecordingStatusOutput() override { Close(); }

  bool is_safe() const { return !is_showing(); }
  drivers::LocalisationState last_state() const { return last_; }
  std::uint64_t changes() const { return changes_; }

 private:
  Status DoOpen() override { return Status::Ok(); }
  // Called when the lit line changes: a new state, or a state after the safe state.
  Status DoWrite(const drivers::StatusLines& lines, Nanoseconds) override {
    for (std::size_t i = 0; i < lines.count; ++i) {
      if (lines.level[i])
        last_ = static_cast<drivers::LocalisationState>(i);
    }
    ++changes_;
    return Status::Ok();
  }
  Status DoSafeState() override { return Status::Ok(); }
  void DoClose() override {}

  drivers::LocalisationState last_ = drivers::LocalisationState::kLost;
  std::uint64_t changes_ = 0;
};

}  // namespace skyloc::app
