// The street as the simulated camera films it: the same drive whatever the camera drops.
#include "skyloc/sim/street_source.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>

namespace skyloc::sim {
namespace {

StreetOptions Options() {
  StreetOptions o;
  o.width = 48;
  o.height = 48;
  o.seed = 3;
  o.speed_jitter = 0.3;
  o.zigzag_deg = 15;
  return o;
}

// Frames a camera drops are frames the robot drove through: frame 10 looks the same and
// is taken at the same place whether or not frames 3..6 were delivered.
TEST(StreetSource, DroppedFramesDoNotMoveTheLaterOnes) {
  FilmedStreet all(Options());
  FilmedStreet dropping(Options());
  ASSERT_TRUE(dropping.camera.InjectFault({drivers::CameraFault::Kind::kDrop, 3, 4}).ok());
  for (FilmedStreet* s : {&all, &dropping}) {
    ASSERT_TRUE(s->camera.Open().ok());
    ASSERT_TRUE(s->camera.Start().ok());
  }
  Result<drivers::Frame> a = all.camera.Capture(std::chrono::seconds(1));
  for (int i = 0; i < 10 && a.ok(); ++i)
    a = all.camera.Capture(std::chrono::seconds(1));
  Result<drivers::Frame> b = dropping.camera.Capture(std::chrono::seconds(1));
  for (int i = 0; i < 6 && b.ok(); ++i)
    b = dropping.camera.Capture(std::chrono::seconds(1));
  ASSERT_TRUE(a.ok() && b.ok());
  ASSERT_EQ(a->sequence, 10u);
  ASSERT_EQ(b->sequence, 10u);
  EXPECT_EQ(dropping.camera.counters().dropped, 4u);
  ASSERT_TRUE(a->pose && b->pose);
  EXPECT_EQ(a->pose->x_m, b->pose->x_m);
  EXPECT_EQ(a->timestamp, b->timestamp);
  EXPECT_TRUE(std::equal(a->image.data, a->image.data + 48 * 48, b->image.data));
}

}  // namespace
}  // namespace skyloc::sim
