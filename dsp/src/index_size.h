// dsp's own helpers for the matchers' index arithmetic (not a public header).
#pragma once

#include <cstddef>
#include <limits>

namespace skyloc::dsp {

// An index or count that the caller has checked is not negative, as a size.
inline std::size_t Sz(int v) {
  return static_cast<std::size_t>(v);
}

inline constexpr float kInf = std::numeric_limits<float>::infinity();

}  // namespace skyloc::dsp
