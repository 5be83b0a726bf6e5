#include "skyloc/drivers/gpio_status_output.h"

#include <gpiod.h>

#include <array>
#include <cerrno>
#include <cstdio>
#include <utility>

namespace skyloc::drivers {
namespace {

constexpr const char* kConsumer = "skyloc";

}  // namespace

void GpiodChipCloser::operator()(gpiod_chip* chip) const {
  ::gpiod_chip_close(chip);
}
void GpiodLineReleaser::operator()(gpiod_line* line) const {
  ::gpiod_line_release(line);
}

GpioStatusOutput::GpioStatusOutput(const GpioStatusOutputConfig& config)
    : StatusOutput(config.mode, "GPIO chip"), config_(config) {
  config_.chip[sizeof(config_.chip) - 1] = '\0';
  char name[96];
  std::snprintf(name, sizeof name, "GPIO chip %s", config_.chip);
  SetName(name);
}

GpioStatusOutput::~GpioStatusOutput() {
  // Last resort: whatever happened, the lines end off (and the owners below release
  // whatever Close() did not).
  Close();
}

Status GpioStatusOutput::DoOpen() {
  errno = 0;
  GpiodChip chip(::gpiod_chip_open_lookup(config_.chip));
  if (chip == nullptr) {
    const int saved = errno != 0 ? errno : ENOENT;
    return Status::FromErrno(saved,
                             "GPIO chip '%s' cannot be opened (list chips with gpiodetect; set "
                             "[status] chip in the configuration)",
                             config_.chip);
  }

  const std::size_t count = line_count();
  gpiod_line_bulk bulk;
  gpiod_line_bulk_init(&bulk);
  // Not ours to release until requested: until then the chip owns them (an early return
  // closes it, and them with it).
  gpiod_line* found[StatusLines::kMaxLines] = {};
  int initial[StatusLines::kMaxLines] = {0, 0, 0};  // requested already in the safe state
  for (std::size_t i = 0; i < count; ++i) {
    found[i] = ::gpiod_chip_get_line(chip.get(), config_.lines[i]);
    if (found[i] == nullptr) {
      const int saved = errno;
      return Status::FromErrno(saved, "GPIO chip %s has no line %u (it has %u lines)", config_.chip,
                               config_.lines[i], ::gpiod_chip_num_lines(chip.get()));
    }
    gpiod_line_bulk_add(&bulk, found[i]);
  }
  const int flags = config_.active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
  if (::gpiod_line_request_bulk_output_flags(&bulk, kConsumer, flags, initial) != 0) {
    const int saved = errno;
    return Status::FromErrno(
        saved,
        "GPIO chip %s: cannot request status lines %u,%u,%u as outputs (in use? see gpioinfo)",
        config_.chip, config_.lines[0], count > 1 ? config_.lines[1] : config_.lines[0],
        count > 2 ? config_.lines[2] : config_.lines[0]);
  }
  // Owned from here on: any return below releases them (locals go in reverse order, the
  // lines before their chip); only a complete Open() hands them to the members.
  std::array<GpiodLineRequest, StatusLines::kMaxLines> lines;
  for (std::size_t i = 0; i < count; ++i)
    lines[i].reset(found[i]);

  GpiodLineRequest button;
  if (config_.button_line >= 0) {
    gpiod_line* line =
        ::gpiod_chip_get_line(chip.get(), static_cast<unsigned>(config_.button_line));
    const int bflags = config_.button_active_low ? GPIOD_LINE_REQUEST_FLAG_ACTIVE_LOW : 0;
    if (line == nullptr ||
        ::gpiod_line_request_both_edges_events_flags(line, kConsumer, bflags) != 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "GPIO chip %s: cannot request button line %d for edge events",
                               config_.chip, config_.button_line);
    }
    button.reset(line);
  }
  std::snprintf(chip_name_, sizeof(chip_name_), "%s", ::gpiod_chip_name(chip.get()));
  chip_ = std::move(chip);
  lines_ = std::move(lines);
  button_ = std::move(button);
  return Status::Ok();
}

Status GpioStatusOutput::Write(const StatusLines& lines) {
  gpiod_line_bulk bulk;
  gpiod_line_bulk_init(&bulk);
  int values[StatusLines::kMaxLines] = {};
  for (std::size_t i = 0; i < lines.count; ++i) {
    gpiod_line_bulk_add(&bulk, lines_[i].get());
    values[i] = lines.level[i] ? 1 : 0;
  }
  if (::gpiod_line_set_value_bulk(&bulk, values) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "GPIO chip %s: setting the status lines", config_.chip);
  }
  return Status::Ok();
}

Status GpioStatusOutput::DoWrite(const StatusLines& lines, Nanoseconds) {
  return Write(lines);
}

Status GpioStatusOutput::DoSafeState() {
  StatusLines off;
  off.count = line_count();
  return Write(off);
}

void GpioStatusOutput::DoClose() {
  // Each owner releases its request; the chip goes after its lines.
  button_.reset();
  for (GpiodLineRequest& line : lines_)
    line.reset();
  chip_.reset();
  chip_name_[0] = '\0';
}

int GpioStatusOutput::button_event_fd() const {
  // Owned by libgpiod, released with the line.
  return button_ != nullptr ? ::gpiod_line_event_get_fd(button_.get()) : -1;
}

Result<bool> GpioStatusOutput::ButtonPressed() const {
  if (button_ == nullptr) {
    return Status::Error(StatusCode::kFailedPrecondition, "GPIO chip %s: no button line open",
                         config_.chip);
  }
  const int value = ::gpiod_line_get_value(button_.get());
  if (value < 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "GPIO chip %s: reading button line %d", config_.chip,
                             config_.button_line);
  }
  return value == 1;
}

Result<ButtonEvent> GpioStatusOutput::DoReadButtonEvent() {
  const timespec no_wait{0, 0};
  const int ready = ::gpiod_line_event_wait(button_.get(), &no_wait);
  if (ready < 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "GPIO chip %s: waiting for button events", config_.chip);
  }
  if (ready == 0) {
    return Status::Error(StatusCode::kDeadlineExceeded, "GPIO chip %s: no button edge pending",
                         config_.chip);
  }
  gpiod_line_event event{};
  if (::gpiod_line_event_read(button_.get(), &event) != 0) {
    const int saved = errno;
    return Status::FromErrno(saved, "GPIO chip %s: reading a button event", config_.chip);
  }
  ButtonEvent out;
  out.pressed = event.event_type == GPIOD_LINE_EVENT_RISING_EDGE;
  out.timestamp = Nanoseconds(static_cast<std::int64_t>(event.ts.tv_sec) * 1'000'000'000 +
                              static_cast<std::int64_t>(event.ts.tv_nsec));
  return out;
}

}  // namespace skyloc::drivers
