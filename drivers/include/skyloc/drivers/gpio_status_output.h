// The localisation state on GPIO lines through libgpiod 1.6 (Debian 12), the character
// device API (/dev/gpiochipN). Built when SKYLOC_WITH_GPIOD.
//
// Which lines light up is StatusPattern's decision (one line per state, or one blinking
// line), shared with SimulatedStatusOutput. Lines are requested as outputs with consumer
// "skyloc" and initial value off, so the robot shows the safe state from the moment the
// lines are ours; Close(), SafeState() and, as a last resort, the destructor drive them
// off again before releasing them. Show() writes only when a level changes (one ioctl,
// no allocation).
//
// Optional button (teach/repeat switch): an input line requested for both edges; its
// event fd can be poll()ed with the camera, and ReadButtonEvent() never blocks.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>

#include "skyloc/drivers/button_event.h"
#include "skyloc/drivers/status_output.h"
#include "skyloc/drivers/status_pattern.h"
#include "skyloc/platform/status.h"

struct gpiod_chip;
struct gpiod_line;

namespace skyloc::drivers {

// Owners of libgpiod handles, so no path (an early return in Open(), the destructor) can
// leak a chip or leave a line requested: the chip is closed, a requested line released,
// when its owner goes. A line belongs to its chip, so a chip's owner must outlive its lines'.
struct GpiodChipCloser {
  void operator()(gpiod_chip* chip) const;
};
struct GpiodLineReleaser {
  void operator()(gpiod_line* line) const;
};
using GpiodChip = std::unique_ptr<gpiod_chip, GpiodChipCloser>;
using GpiodLineRequest = std::unique_ptr<gpiod_line, GpiodLineReleaser>;

struct GpioStatusOutputConfig {
  char chip[64] = "gpiochip0";  // name ("gpiochip0"), number ("0"), path or label
  StatusLineMode mode = StatusLineMode::kLinePerState;
  // Line offsets: LOST, SEARCHING, LOCALISED in per-state mode; blink mode uses lines[0].
  std::array<unsigned, 3> lines{0, 1, 2};
  bool active_low = false;         // an indicator lit by driving the pin low
  int button_line = -1;            // offset of the button input; -1: no button
  bool button_active_low = false;  // pressed = low (button to ground with a pull-up)
};

class GpioStatusOutput final : public StatusOutput {
 public:
  explicit GpioStatusOutput(const GpioStatusOutputConfig& config);
  ~GpioStatusOutput() override;

  // The kernel's name of the opened chip ("gpiochip3"); empty before Open().
  const char* chip_name() const { return chip_name_; }

  // --- the button (kFailedPrecondition when none is configured or not open) ---
  int button_event_fd() const;
  Result<bool> ButtonPressed() const;

 private:
  Status DoOpen() override;
  Status DoWrite(const StatusLines& lines, Nanoseconds now) override;
  Status DoSafeState() override;
  void DoClose() override;
  bool DoHasButton() const override { return button_ != nullptr; }
  // The next edge, or kDeadlineExceeded when none is pending. Timestamps are the
  // kernel's (CLOCK_MONOTONIC on Linux >= 5.7).
  Result<ButtonEvent> DoReadButtonEvent() override;

  Status Write(const StatusLines& lines);

  GpioStatusOutputConfig config_;
  // Declared before the lines: members are destroyed in reverse, lines first.
  GpiodChip chip_;
  std::array<GpiodLineRequest, StatusLines::kMaxLines> lines_;  // requested outputs
  GpiodLineRequest button_;
  char chip_name_[32] = {};
};

}  // namespace skyloc::drivers
