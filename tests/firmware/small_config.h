// The small configuration the frame-loop tests share: a 64x64 camera, 16 bands and a
// 400-frame route, so that a whole teach and repeat takes milliseconds; and the simulated
// street they drive.
#pragma once

#include <cstdint>

#include "firmware/config.h"
#include "skyloc/sim/street_source.h"

namespace skyloc::firmware::testing {

inline Config SmallConfig() {
  Config c = DefaultConfig();
  c.camera.capture.width = 64;
  c.camera.capture.height = 64;
  c.descriptor.bands = 16;
  c.descriptor.rings = 8;
  c.descriptor.longitudes = 32;
  c.capacities.route_frames = 400;
  c.route_db.flush_every = 25;
  return c;
}

// The 64x64 street of world seed 7, driven as run `run_seed` for `frames` frames (0: endless).
inline sim::StreetOptions SmallStreet(std::uint64_t run_seed = 0, std::uint64_t frames = 0) {
  sim::StreetOptions o;
  o.width = 64;
  o.height = 64;
  o.seed = 7;
  o.run_seed = run_seed;
  o.frames = frames;
  return o;
}

}  // namespace skyloc::firmware::testing
