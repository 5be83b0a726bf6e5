#include "firmware/button.h"

namespace skyloc::firmware {

void ButtonDebouncer::OnEdge(const drivers::ButtonEvent& edge) {
  // A release that lasted the debounce time before this edge arms the next press (the
  // caller may not have polled in between).
  if (!active_ && edge.timestamp - since_ >= debounce_)
    reported_ = false;
  // A repeated edge of the same direction (an event lost in between) restarts the window
  // too: the line's level was not steady.
  active_ = edge.pressed;
  since_ = edge.timestamp;
}

bool ButtonDebouncer::TakePress(Nanoseconds now) {
  const bool steady = now - since_ >= debounce_;
  if (!active_) {
    if (steady)
      reported_ = false;
    return false;
  }
  if (reported_ || !steady)
    return false;
  reported_ = true;
  return true;
}

}  // namespace skyloc::firmware
