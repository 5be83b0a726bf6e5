// The circle's constants, once: every degree-radian conversion in skyloc uses these (the
// same doubles as std::numbers::pi and 3.14159265358979323846, so no result moves).
#pragma once

#include <numbers>

namespace skyloc::dsp {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDegToRad = kPi / 180.0;
inline constexpr double kRadToDeg = 180.0 / kPi;

}  // namespace skyloc::dsp
