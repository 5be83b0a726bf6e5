#include "skyloc/drivers/simulated_status_output.h"

#include <sys/eventfd.h>
#include <unistd.h>

#include <cerrno>

namespace skyloc::drivers {

SimulatedStatusOutput::SimulatedStatusOutput(const SimulatedStatusOutputConfig& config,
                                             const Clock* clock)
    : StatusOutput(config.mode, "simulated status output"),
      config_(config),
      clock_(clock),
      recorded_(levels()) {}

SimulatedStatusOutput::~SimulatedStatusOutput() {
  Close();
}

Status SimulatedStatusOutput::DoOpen() {
  if (clock_ == nullptr || config_.history_capacity == 0) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "simulated status output: needs a clock and history_capacity > 0");
  }
  if (history_storage_.size() != config_.history_capacity) {
    if (Status s = history_storage_.Allocate(config_.history_capacity); !s.ok())
      return s.AddContext("simulated status output history");
  }
  history_.SetStorage(history_storage_.span());
  if (config_.has_button) {
    const int fd = ::eventfd(0, EFD_CLOEXEC | EFD_NONBLOCK);
    if (fd < 0) {
      const int saved = errno;
      return Status::FromErrno(saved, "simulated status output: eventfd for the button");
    }
    button_fd_.reset(fd);
    button_events_.Clear();
    button_level_ = false;
  }
  // Lines are requested in the safe state, and that counts as a recorded level.
  recorded_ = levels();
  const Nanoseconds now = clock_->Now();
  for (std::size_t i = 0; i < recorded_.count; ++i)
    history_.PushOverwrite(LineChange{now, static_cast<std::uint8_t>(i), false});
  return Status::Ok();
}

void SimulatedStatusOutput::Record(const StatusLines& lines, Nanoseconds now) {
  for (std::size_t i = 0; i < lines.count; ++i) {
    if (lines.level[i] != recorded_.level[i])
      history_.PushOverwrite(LineChange{now, static_cast<std::uint8_t>(i), lines.level[i]});
  }
  recorded_ = lines;
}

Status SimulatedStatusOutput::DoWrite(const StatusLines& lines, Nanoseconds now) {
  Record(lines, now);
  return Status::Ok();
}

Status SimulatedStatusOutput::DoSafeState() {
  StatusLines off = recorded_;
  off.level.fill(false);
  Record(off, clock_->Now());
  return Status::Ok();
}

void SimulatedStatusOutput::DoClose() {
  button_fd_.reset();
}

void SimulatedStatusOutput::InjectButton(bool pressed) {
  if (!button_fd_.is_valid() || pressed == button_level_)
    return;
  button_level_ = pressed;
  button_events_.PushOverwrite(ButtonEvent{pressed, clock_->Now()});
  const std::uint64_t one = 1;
  (void)!::write(button_fd_.get(), &one, sizeof(one));
}

Result<bool> SimulatedStatusOutput::ButtonPressed() const {
  if (!button_fd_.is_valid()) {
    return Status::Error(StatusCode::kFailedPrecondition,
                         "simulated status output: no button configured, or not open");
  }
  return button_level_;
}

Result<ButtonEvent> SimulatedStatusOutput::DoReadButtonEvent() {
  if (button_events_.empty()) {
    return Status::Error(StatusCode::kDeadlineExceeded,
                         "simulated status output: no button edge pending");
  }
  const ButtonEvent event = button_events_[0];
  button_events_.PopOldest();
  if (button_events_.empty()) {
    std::uint64_t count = 0;  // drain the eventfd so poll() stops reporting it readable
    (void)!::read(button_fd_.get(), &count, sizeof(count));
  }
  return event;
}

}  // namespace skyloc::drivers
