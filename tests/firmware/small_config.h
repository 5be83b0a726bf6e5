// The small configuration the frame-loop tests share: a 64x64 camera, 16 bands and a
// 400-frame route, so that a whole teach and repeat takes milliseconds.
#pragma once

#include "firmware/config.h"

namespace skyloc::firmware::testing {

inline Config SmallConfig() {
  Config c = DefaultConfig();
  c.camera.width = 64;
  c.camera.height = 64;
  c.descriptor.bands = 16;
  c.descriptor.rings = 8;
  c.descriptor.longitudes = 32;
  c.capacities.route_frames = 400;
  c.route_db.flush_every = 25;
  return c;
}

}  // namespace skyloc::firmware::testing
