// The one place that decides which status lines are lit: a pure function of
// (state, confidence, time). GpioStatusOutput and SimulatedStatusOutput both call it,
// so the simulated twin shows exactly what the robot's LEDs show.
//
// Two modes (chosen in the configuration):
//   kLinePerState  three lines: LOST, SEARCHING, LOCALISED; exactly the current one is on.
//   kBlink         one line whose blink pattern encodes state and confidence:
//                    LOST       a 100 ms flash every 2 s      (alive, but lost)
//                    SEARCHING  1 Hz, 50 % duty
//                    LOCALISED  2 Hz at confidence 0 up to 10 Hz at confidence 1, 50 % duty
//                  Blinking is phase-locked to the monotonic clock (time modulo the
//                  period), so the pattern needs no state and restarts cleanly.
//                  NextEdge() says when the line next changes, so the frame loop can
//                  wake for it between frames (a blink faster than the frames, or a
//                  100 ms flash between two frames 500 ms apart, still shows).
// The safe state, in both modes, is every line off (inactive).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>

#include "skyloc/dsp/localisation_state.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"

namespace skyloc::drivers {

// The state machine's own states (dsp/localisation_state.h): what the lines show is what
// it decided, with no second enum to translate into.
using dsp::LocalisationState;
using dsp::LocalisationStateName;

enum class StatusLineMode : std::uint8_t { kLinePerState, kBlink };

struct StatusLines {
  static constexpr std::size_t kMaxLines = 3;
  std::array<bool, kMaxLines> level{};  // logical level: true = indicator on
  std::size_t count = 0;                // lines in use: 3 (per state) or 1 (blink)

  bool operator==(const StatusLines&) const = default;
};

class StatusPattern {
 public:
  explicit StatusPattern(StatusLineMode mode) : mode_(mode) {}

  StatusLineMode mode() const { return mode_; }
  std::size_t line_count() const { return mode_ == StatusLineMode::kBlink ? 1 : 3; }

  // The line levels for `state` at `now`. `confidence` is clamped to [0, 1].
  StatusLines Levels(LocalisationState state, float confidence, Nanoseconds now) const;
  // Every line off.
  StatusLines Safe() const;

  // The blink period and on-time of the single line in kBlink mode (exposed for tests
  // and for docs/DRIVERS.md).
  struct Blink {
    Nanoseconds period;
    Nanoseconds on_time;
  };
  static Blink BlinkFor(LocalisationState state, float confidence);
  // The first time after `now` at which Levels(state, confidence, .) differs from its
  // value at `now`: the next blink edge; Nanoseconds::max() in kLinePerState mode.
  Nanoseconds NextEdge(LocalisationState state, float confidence, Nanoseconds now) const;

 private:
  StatusLineMode mode_;
};

// The one name of each mode: "per-state", "blink" ([status] encoding in the configuration,
// the test environment).
constexpr const char* StatusLineModeName(StatusLineMode mode) {
  return mode == StatusLineMode::kBlink ? "blink" : "per-state";
}
// The mode StatusLineModeName gives `text`; kInvalidArgument for any other text.
Result<StatusLineMode> ParseStatusLineMode(const char* text);

}  // namespace skyloc::drivers
