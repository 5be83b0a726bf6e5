// An edge on the optional teach/repeat button input of a status output.
#pragma once

#include "skyloc/platform/clock.h"

namespace skyloc::drivers {

struct ButtonEvent {
  bool pressed = false;      // true: the line became active (rising edge, after active-low)
  Nanoseconds timestamp{0};  // CLOCK_MONOTONIC (real) or the injected clock (simulated)
};

}  // namespace skyloc::drivers
