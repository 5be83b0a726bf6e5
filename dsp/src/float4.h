// Four floats as one SIMD register (GCC/Clang vector extension: SSE2 on x86-64, NEON on
// aarch64, plain code elsewhere), for dsp/src only. Element-wise IEEE operations, so the
// results are the same as the scalar loop's on every machine.
#pragma once

#include <cstdint>
#include <cstring>

namespace skyloc::dsp::simd {

using Float4 = float __attribute__((vector_size(16)));
using Bits4 = std::uint32_t __attribute__((vector_size(16)));

inline Float4 Load4(const float* p) {
  Float4 v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

inline void Store4(float* p, Float4 v) {
  std::memcpy(p, &v, sizeof v);
}

inline Float4 Abs4(Float4 v) {
  Bits4 bits;
  std::memcpy(&bits, &v, sizeof bits);
  bits &= 0x7FFFFFFFu;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

// Lane-wise b < a ? b : a (a when either is NaN): minps / fmin-free NEON compare and select,
// without the branch a scalar std::min becomes.
inline Float4 Min4(Float4 a, Float4 b) {
  return b < a ? b : a;
}

}  // namespace skyloc::dsp::simd
