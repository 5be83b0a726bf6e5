// The route's integer codes (seqslam.h, EncodeCodes): plain scalar code, apart from the
// SIMD scan in seqslam.cpp, so the route database's fuzz target (clang) builds it too.
#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>

#include "skyloc/dsp/seqslam.h"

namespace skyloc::dsp {
namespace {}  // namespace

template <typename Code>
std::int8_t EncodeCodes(std::span<const float> row, std::span<Code> codes) {
  constexpr bool kSquareLaw = sizeof(Code) == 1;
  constexpr float kMaxCode = sizeof(Code) == 1 ? 255.0f : 65535.0f;
  // The largest scaled value whose code is at most kMaxCode: 65535.5 (linear) or 255.5^2
  // (square law); fitting max(row) / 2^e below it with the smallest e puts the largest
  // code at 32768.. (linear) or 181.. (square law).
  constexpr float kLimit = kSquareLaw ? 255.5f * 255.5f : 65535.5f;
  float max = 0.0f;
  for (const float v : row)
    max = v > max ? v : max;  // NaN and negative values never raise it
  int exponent = kCodeMinExponent;
  if (max > 0.0f && std::isfinite(max)) {
    // max = m 2^e2 with m in [0.5, 1): max / 2^(e2 - 16) = m 2^16 is in [2^15, 2^16); one
    // step up when it reaches the limit.
    int e2 = 0;
    (void)std::frexp(max, &e2);
    exponent = e2 - 16;
    if (std::ldexp(max, -exponent) >= kLimit)
      ++exponent;
    exponent = std::clamp(exponent, kCodeMinExponent, kCodeMaxExponent);
  }
  for (std::size_t i = 0; i < row.size(); ++i) {
    const float v = row[i];
    // ldexp by a power of two is exact, sqrt is correctly rounded (IEEE), nearbyint rounds
    // half to even (the default mode): the same codes on every machine.
    float code = 0.0f;
    if (v > 0.0f) {
      const float scaled = std::ldexp(v, -exponent);
      code = std::nearbyint(kSquareLaw ? std::sqrt(scaled) : scaled);
    }
    codes[i] = static_cast<Code>(std::min(code, kMaxCode));
  }
  return static_cast<std::int8_t>(exponent);
}

template <typename Code>
void DecodeCodes(std::span<const Code> codes, std::int8_t exponent, std::span<float> out) {
  const float scale = CodeScale(exponent);
  for (std::size_t i = 0; i < codes.size(); ++i) {
    const float c = static_cast<float>(codes[i]);
    out[i] = (sizeof(Code) == 1 ? c * c : c) * scale;
  }
}

template std::int8_t EncodeCodes(std::span<const float>, std::span<std::uint8_t>);
template std::int8_t EncodeCodes(std::span<const float>, std::span<std::uint16_t>);
template void DecodeCodes(std::span<const std::uint8_t>, std::int8_t, std::span<float>);
template void DecodeCodes(std::span<const std::uint16_t>, std::int8_t, std::span<float>);

}  // namespace skyloc::dsp
