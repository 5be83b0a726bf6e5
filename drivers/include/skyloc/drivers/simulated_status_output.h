// The status output's simulated twin: the same StatusPattern as the GPIO driver, with
// every line change recorded (time, line, level) in a fixed-capacity history allocated
// in Open(). When the history is full the oldest change is overwritten and counted in
// overwritten(), so a test can tell a complete record from a truncated one.
//
// The simulated button: PressButton()/ReleaseButton() queue an edge and make
// button_event_fd() readable (an eventfd), so code that polls the real GPIO driver's
// event fd works unchanged against the twin.
#pragma once

#include <cstddef>
#include <cstdint>

#include "skyloc/drivers/button_event.h"
#include "skyloc/drivers/status_output.h"
#include "skyloc/drivers/status_pattern.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/fixed_array.h"
#include "skyloc/platform/ring_buffer.h"
#include "skyloc/platform/status.h"
#include "skyloc/platform/unique_fd.h"

namespace skyloc::drivers {

struct LineChange {
  Nanoseconds time{0};
  std::uint8_t line = 0;  // index into the configured lines (0..2), not a chip offset
  bool level = false;     // logical: true = indicator on
};

struct SimulatedStatusOutputConfig {
  StatusLineMode mode = StatusLineMode::kLinePerState;
  std::size_t history_capacity = 1024;
  bool has_button = false;
};

class SimulatedStatusOutput final : public StatusOutput {
 public:
  static constexpr std::size_t kMaxButtonEvents = 16;

  // `clock` stamps the changes made by Open/SafeState/Close (Show and Refresh use their
  // `now`) and the button's edges.
  SimulatedStatusOutput(const SimulatedStatusOutputConfig& config, const Clock* clock);
  ~SimulatedStatusOutput() override;

  // Current logical level of line `line` (false when closed: released lines are off).
  bool Level(std::size_t line) const {
    return is_open() && line < levels().count && levels().level[line];
  }
  const RingBuffer<LineChange>& history() const { return history_; }
  std::uint64_t overwritten() const { return history_.overwritten(); }
  void ClearHistory() { history_.Clear(); }

  // --- the button ---
  int button_event_fd() const { return button_fd_.get(); }
  Result<bool> ButtonPressed() const;
  void PressButton() { InjectButton(true); }
  void ReleaseButton() { InjectButton(false); }

 private:
  Status DoOpen() override;
  Status DoWrite(const StatusLines& lines, Nanoseconds now) override;
  Status DoSafeState() override;
  void DoClose() override;
  bool DoHasButton() const override { return button_fd_.is_valid(); }
  Result<ButtonEvent> DoReadButtonEvent() override;  // kDeadlineExceeded when none pending

  void Record(const StatusLines& lines, Nanoseconds now);
  void InjectButton(bool pressed);

  SimulatedStatusOutputConfig config_;
  const Clock* clock_;
  StatusLines recorded_;  // the levels the history ends with
  FixedArray<LineChange> history_storage_;
  RingBuffer<LineChange> history_;

  UniqueFd button_fd_;
  bool button_level_ = false;
  std::array<ButtonEvent, kMaxButtonEvents> button_storage_{};
  RingBuffer<ButtonEvent> button_events_{button_storage_};
};

}  // namespace skyloc::drivers
