#include "skyloc/drivers/status_output.h"

#include <cstdio>

namespace skyloc::drivers {

StatusOutput::StatusOutput(StatusLineMode mode, const char* name)
    : pattern_(mode), levels_(pattern_.Safe()) {
  SetName(name);
}

void StatusOutput::SetName(const char* name) {
  std::snprintf(name_, sizeof name_, "%s", name != nullptr ? name : "status output");
}

Status StatusOutput::Open() {
  if (open_)
    return Status::Error(StatusCode::kFailedPrecondition, "%s: already open", name_);
  SKYLOC_TRY(DoOpen());
  open_ = true;
  showing_ = false;
  levels_ = pattern_.Safe();
  return Status::Ok();
}

Status StatusOutput::Counted(Status s) {
  ++counters_.writes;
  if (!s.ok())
    ++counters_.failures;
  return s;
}

Status StatusOutput::Apply(Nanoseconds now) {
  const StatusLines lines = pattern_.Levels(state_, confidence_, now);
  if (lines == levels_)
    return Status::Ok();
  SKYLOC_TRY(Counted(DoWrite(lines, now)));
  levels_ = lines;
  return Status::Ok();
}

Status StatusOutput::Show(LocalisationState state, float confidence, Nanoseconds now) {
  if (!open_)
    return Status::Error(StatusCode::kFailedPrecondition, "%s: Show() before Open()", name_);
  state_ = state;
  confidence_ = confidence;
  showing_ = true;
  return Apply(now);
}

Status StatusOutput::Refresh(Nanoseconds now) {
  if (!showing_)
    return Status::Ok();
  return Apply(now);
}

Nanoseconds StatusOutput::NextChange(Nanoseconds now) const {
  if (!showing_)
    return kNever;
  return pattern_.NextEdge(state_, confidence_, now);
}

Status StatusOutput::SafeState() {
  showing_ = false;
  if (!open_)
    return Status::Ok();
  // Whatever the lines are believed to show: a failed write may have left them anywhere.
  SKYLOC_TRY(Counted(DoSafeState()));
  levels_ = pattern_.Safe();
  return Status::Ok();
}

void StatusOutput::Close() {
  if (!open_)
    return;
  (void)SafeState();
  DoClose();
  open_ = false;
  levels_ = pattern_.Safe();
}

Result<ButtonEvent> StatusOutput::ReadButtonEvent() {
  if (!has_button()) {
    return Status::Error(StatusCode::kFailedPrecondition, "%s: no button configured, or not open",
                         name_);
  }
  return DoReadButtonEvent();
}

Result<ButtonEvent> StatusOutput::DoReadButtonEvent() {
  return Status::Error(StatusCode::kFailedPrecondition, "%s has no button", name_);
}

}  // namespace skyloc::drivers
