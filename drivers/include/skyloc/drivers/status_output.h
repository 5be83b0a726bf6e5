// Where the localisation state goes: GPIO lines on the robot, a recording twin in tests.
// Show() is called once per frame from the pipeline thread and must not allocate or block.
#pragma once

#include <cstdint>

#include "skyloc/drivers/button_event.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// The state machine's own states (dsp/localisation_state.h): what the lines show is what
// it decided, with no second enum to translate into.
using dsp::LocalisationState;
using dsp::LocalisationStateName;

class StatusOutput {
 public:
  virtual ~StatusOutput() = default;
  StatusOutput(const StatusOutput&) = delete;
  StatusOutput& operator=(const StatusOutput&) = delete;

  // Requests the lines; leaves them in the safe state.
  virtual Status Open() = 0;
  // confidence in [0, 1].
  virtual Status Show(LocalisationState state, float confidence, Nanoseconds now) = 0;
  // Drives every line to its defined safe state (all indicators off). Safe to call at any
  // time, repeatedly, and from the shutdown path after a fatal error.
  virtual Status SafeState() = 0;
  virtual void Close() = 0;

  // The optional teach button on the same chip (GpioStatusOutput, SimulatedStatusOutput):
  // whether one is configured and open, and its next edge without blocking
  // (kDeadlineExceeded when none is pending). Outputs without a button keep these.
  virtual bool has_button() const { return false; }
  virtual Result<ButtonEvent> ReadButtonEvent() {
    return Status::Error(StatusCode::kFailedPrecondition, "this status output has no button");
  }

 protected:
  StatusOutput() = default;
};

}  // namespace skyloc::drivers
