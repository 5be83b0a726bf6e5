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

  Status Open() override;
  Status Show(LocalisationState state, float confidence, Nanoseconds now) override;
  Status SafeState() override;
  void Close() override;

  bool is_open() const { return chip_ != nullptr; }
  // The kernel's name of the opened chip ("gpiochip3"); empty before Open().
  const char* chip_name() const { return chip_name_; }
  const StatusLines& levels() const { return levels_; }

  // --- the button (kFailedPrecondition when none is configured or not open) ---
  int button_event_fd() const { return button_fd_; }
  Result<bool> ButtonPressed() const;
  // The next edge, or kDeadlineExceeded when none is pending. Timestamps are the
  // kernel's (CLOCK_MONOTONIC on Linux >= 5.7).
  bool has_button() const override { return button_ != nullptr; }
  Result<ButtonEvent> ReadButtonEvent() override;

 private:
  Status Write(const StatusLines& lines);

  GpioStatusOutputConfig config_;
  StatusPattern pattern_;
  // Declared before the lines: members are destroyed in reverse, lines first.
  GpiodChip chip_;
  std::array<GpiodLineRequest, StatusLines::kMaxLines> lines_;  // requested outputs
  GpiodLineRequest button_;
  int button_fd_ = -1;  // owned by libgpiod (released with the line)
  StatusLines levels_;
  char chip_name_[32] = {};
};

}  // namespace skyloc::drivers
