#include "skyloc/drivers/status_pattern.h"

#include <cmath>
#include <cstring>

namespace skyloc::drivers {

StatusPattern::Blink StatusPattern::BlinkFor(LocalisationState state, float confidence) {
  using std::chrono::milliseconds;
  switch (state) {
    case LocalisationState::kLost:
      return {milliseconds(2000), milliseconds(100)};
    case LocalisationState::kSearching:
      return {milliseconds(1000), milliseconds(500)};
    case LocalisationState::kLocalised: {
      const float c = std::isnan(confidence) ? 0.0f : std::fmin(1.0f, std::fmax(0.0f, confidence));
      // 2 Hz .. 10 Hz: period 500 ms .. 100 ms, rounded to whole microseconds.
      const double hz = 2.0 + 8.0 * static_cast<double>(c);
      const auto period = Nanoseconds(static_cast<std::int64_t>(std::llround(1e6 / hz)) * 1000);
      return {period, period / 2};
    }
  }
  return {milliseconds(1000), Nanoseconds(0)};
}

StatusLines StatusPattern::Safe() const {
  StatusLines lines;
  lines.count = line_count();
  return lines;
}

StatusLines StatusPattern::Levels(LocalisationState state, float confidence,
                                  Nanoseconds now) const {
  StatusLines lines = Safe();
  if (mode_ == StatusLineMode::kLinePerState) {
    const auto line = static_cast<std::size_t>(state);
    if (line < lines.count)  // an out-of-range state (memory corruption) shows nothing
      lines.level[line] = true;
    return lines;
  }
  const Blink blink = BlinkFor(state, confidence);
  Nanoseconds phase = now % blink.period;
  if (phase < Nanoseconds(0))
    phase += blink.period;
  lines.level[0] = phase < blink.on_time;
  return lines;
}

Nanoseconds StatusPattern::NextEdge(LocalisationState state, float confidence,
                                    Nanoseconds now) const {
  if (mode_ != StatusLineMode::kBlink)
    return Nanoseconds::max();
  const Blink blink = BlinkFor(state, confidence);
  Nanoseconds phase = now % blink.period;
  if (phase < Nanoseconds(0))
    phase += blink.period;
  // On until on_time, off until the period ends.
  if (phase < blink.on_time)
    return now + (blink.on_time - phase);
  return now + (blink.period - phase);
}

Result<StatusLineMode> ParseStatusLineMode(const char* text) {
  for (const StatusLineMode mode : {StatusLineMode::kLinePerState, StatusLineMode::kBlink}) {
    if (text != nullptr && std::strcmp(text, StatusLineModeName(mode)) == 0)
      return mode;
  }
  return Status::Error(
      StatusCode::kInvalidArgument, "status line mode '%s' is not known: use \"%s\" or \"%s\"",
      text != nullptr ? text : "", StatusLineModeName(StatusLineMode::kLinePerState),
      StatusLineModeName(StatusLineMode::kBlink));
}

}  // namespace skyloc::drivers
