// Where the localisation state goes: GPIO lines on the robot, a recording twin in tests.
// Shaped like Camera: the public methods are non-virtual and check the call order once,
// here, so every implementation behaves the same way to the frame loop; implementations
// override the private Do* hooks only, and only write the levels they are given.
//
//   Closed --Open()--> Open (safe) --Show()--> Open (showing) --SafeState()--> Open (safe)
//   any --Close()--> Closed (the lines off, then released)
//
// Which lines are lit is StatusPattern's decision (status_pattern.h), made here from the
// state shown last and the time, so the GPIO driver and the simulated twin cannot differ.
// A blinking line changes between frames: Refresh(now) applies the pattern at `now` to the
// state shown last, and NextChange(now) says when the lines next change if nothing new is
// shown, so the frame loop wakes at the earlier of the next frame and the next blink edge
// (docs/FIRMWARE.md, "The status lines between frames").
//
// Show(), Refresh() and SafeState() are called from the frame loop's thread and never
// allocate or block; a hook is called only when a level changes (SafeState always).
#pragma once

#include <cstdint>

#include "skyloc/drivers/button_event.h"
#include "skyloc/drivers/status_pattern.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// Health counters every status output keeps (the simulated twin too); the session prints
// them with the other devices' (firmware/device_report.h).
struct StatusOutputCounters {
  std::uint64_t writes = 0;    // level changes and safe states driven onto the lines
  std::uint64_t failures = 0;  // of those, the ones the device refused
};

class StatusOutput {
 public:
  // What NextChange() returns when the lines stay as they are until something new is
  // shown (one line per state, the safe state, closed).
  static constexpr Nanoseconds kNever = Nanoseconds::max();

  virtual ~StatusOutput() = default;
  StatusOutput(const StatusOutput&) = delete;
  StatusOutput& operator=(const StatusOutput&) = delete;

  // Requests the lines; leaves them in the safe state. kFailedPrecondition when open.
  Status Open();
  // Shows `state` (confidence in [0, 1]) from `now` on. kFailedPrecondition when closed.
  Status Show(LocalisationState state, float confidence, Nanoseconds now);
  // The state shown last, as the pattern has it at `now` (a blink edge since the last
  // Show). Nothing to do, and Ok, when closed or in the safe state.
  Status Refresh(Nanoseconds now);
  // The first time after `now` at which Refresh() would change a level; kNever when none.
  Nanoseconds NextChange(Nanoseconds now) const;
  // Drives every line to its defined safe state (all indicators off), whatever the lines
  // are believed to show. Safe to call at any time, repeatedly (Ok when closed), and from
  // the shutdown path after a fatal error.
  Status SafeState();
  // The safe state, then the lines released. Harmless when closed.
  void Close();

  // Who the lines are ("GPIO chip gpiochip0", "simulated status output").
  const char* name() const { return name_; }
  bool is_open() const { return open_; }
  // Showing a state (not the safe state, not closed).
  bool is_showing() const { return showing_; }
  StatusLineMode mode() const { return pattern_.mode(); }
  std::size_t line_count() const { return pattern_.line_count(); }
  // The levels last written (the safe state when closed).
  const StatusLines& levels() const { return levels_; }
  const StatusOutputCounters& counters() const { return counters_; }

  // The optional teach button on the same chip (GpioStatusOutput, SimulatedStatusOutput):
  // whether one is configured and open, and its next edge without blocking
  // (kDeadlineExceeded when none is pending; kFailedPrecondition without an open button).
  bool has_button() const { return open_ && DoHasButton(); }
  Result<ButtonEvent> ReadButtonEvent();

 protected:
  // `name` starts every error message ("GPIO chip gpiochip0", "simulated status output").
  StatusOutput(StatusLineMode mode, const char* name);
  void SetName(const char* name);

 private:
  // Request the lines, already in the safe state (all off).
  virtual Status DoOpen() = 0;
  // Drive the lines to `lines` (count == line_count()); `now` is when (Show's or
  // Refresh's time). Called only when a level differs from levels().
  virtual Status DoWrite(const StatusLines& lines, Nanoseconds now) = 0;
  // Drive every line off, unconditionally.
  virtual Status DoSafeState() = 0;
  // Release the lines (already off).
  virtual void DoClose() = 0;
  virtual bool DoHasButton() const { return false; }
  virtual Result<ButtonEvent> DoReadButtonEvent();

  Status Apply(Nanoseconds now);

  // Counts one write of the lines and, when `s` is an error, one failure; returns `s`.
  Status Counted(Status s);

  StatusPattern pattern_;
  StatusLines levels_;
  StatusOutputCounters counters_;
  bool open_ = false;
  bool showing_ = false;
  LocalisationState state_ = LocalisationState::kLost;
  float confidence_ = 0;
  char name_[64] = {};
};

}  // namespace skyloc::drivers
