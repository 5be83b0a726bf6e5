// The teach button's debouncing: pure logic on timestamped edges, no I/O and no clock of
// its own (the caller passes `now`), so tests drive it with edge sequences.
//
// A press is accepted when the line has been active for `debounce` since its last edge
// with no opposite edge in between; contact bounce (edges closer together than that) is
// ignored, and a press is accepted once however long the button is held: the next press
// needs a release that stays released for `debounce` too, so a glitch while the button
// is held is not a second press.
#pragma once

#include "skyloc/drivers/button_event.h"
#include "skyloc/platform/clock.h"

namespace skyloc::firmware {

class ButtonDebouncer {
 public:
  explicit ButtonDebouncer(Nanoseconds debounce) : debounce_(debounce) {}

  // An edge from the driver, in time order.
  void OnEdge(const drivers::ButtonEvent& edge);
  // True once per accepted press, at the first call with now >= last edge + debounce.
  bool TakePress(Nanoseconds now);

  bool active() const { return active_; }

 private:
  Nanoseconds debounce_;
  bool active_ = false;
  Nanoseconds since_{0};   // the last edge's time
  bool reported_ = false;  // accepted as a press; cleared by a steady release
};

}  // namespace skyloc::firmware
