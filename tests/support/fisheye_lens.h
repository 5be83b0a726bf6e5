// The tests' fisheye: an equidistant 185-degree lens filling a width x height image.
#pragma once

#include <gtest/gtest.h>

#include "skyloc/dsp/lens.h"

namespace skyloc::testing {

inline dsp::Lens FisheyeLens(int width, int height) {
  dsp::LensParams p;
  p.width = width;
  p.height = height;
  p.fov_deg = 185.0;
  dsp::Lens lens;
  EXPECT_EQ(lens.Init(p), dsp::LensError::kOk);
  return lens;
}

}  // namespace skyloc::testing
