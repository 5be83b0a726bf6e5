// Where the localisation state goes: GPIO lines on the robot, a recording twin in tests.
// Show() is called once per frame from the pipeline thread and must not allocate or block.
#pragma once

#include <cstdint>

#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

enum class LocalisationState : std::uint8_t { kLost, kSearching, kLocalised };

const char* LocalisationStateName(LocalisationState state);

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

 protected:
  StatusOutput() = default;
};

}  // namespace skyloc::drivers
