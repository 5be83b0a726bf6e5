// A route taught on the small street (SmallStreet) through the teach-mode pipeline, as
// teach does: the frame-loop and outputs tests repeat against it.
#pragma once

#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>

#include "firmware/frame_loop.h"
#include "skyloc/sim/street_source.h"
#include "small_config.h"

namespace skyloc::firmware::testing {

// Teaches `frames` frames of run `run_seed` of the street into `route` (capacity 400), each
// with its pose (so a repeat against it reports its distance along the route).
inline void TeachSmallStreet(Pipeline& pipeline, std::uint64_t run_seed, std::uint64_t frames,
                             RouteFrames* route) {
  sim::FilmedStreet filmed(SmallStreet(run_seed, frames));
  drivers::Camera& camera = filmed.camera;
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Start().ok());
  ASSERT_TRUE(route
                  ->Allocate(400, static_cast<std::size_t>(pipeline.dim()),
                             pipeline.strip_settings().columns)
                  .ok());
  for (Result<drivers::Frame> f = camera.Capture(std::chrono::seconds(1)); f.ok();
       f = camera.Capture(std::chrono::seconds(1))) {
    FrameResult r;
    ASSERT_TRUE(pipeline.Describe(f->image, &r).ok());
    RouteFrameMeta meta;
    meta.pose = *f->pose;
    ASSERT_TRUE(route->Append(meta, pipeline.descriptor(), pipeline.strip()));
  }
}

}  // namespace skyloc::firmware::testing
