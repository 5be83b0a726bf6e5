// The circle's constants, once: a named degree-radian factor anywhere in skyloc is one of
// these (the same doubles as std::numbers::pi and 3.14159265358979323846). An expression
// written as x * 180.0 / pi rounds differently from x * kRadToDeg, so such expressions stay
// as written: rewriting them would move results.
#pragma once

#include <numbers>

namespace skyloc::dsp {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDegToRad = kPi / 180.0;
inline constexpr double kRadToDeg = 180.0 / kPi;

}  // namespace skyloc::dsp
