// pi and one degree in radians, for the tests' angles (one definition for every test file,
// which a unity build of a test folder needs).
#pragma once

#include <numbers>

namespace skyloc {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kDeg = std::numbers::pi / 180.0;

}  // namespace skyloc
