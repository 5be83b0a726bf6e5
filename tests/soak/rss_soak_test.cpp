// Flat memory over a long run: 100,000 simulated frames through the repeat loop; the
// resident set after the run may not exceed the one after the warm-up by more than a few
// pages, and the loop allocates nothing. Label `slow` (about 15 s in Release).
#include <gtest/gtest.h>

#include <cstdio>

#include "firmware/frame_loop.h"
#include "firmware/output_publisher.h"
#include "skyloc/drivers/simulated_status_output.h"
#include "skyloc/platform/alloc_counter.h"
#include "skyloc/platform/process_memory.h"
#include "skyloc/platform/signals.h"
#include "skyloc/sim/street_source.h"

namespace skyloc::firmware {
namespace {

TEST(Soak, HundredThousandFramesKeepMemoryFlat) {
  ClearSignalFlags();
  Config config = DefaultConfig();
  config.camera.capture.width = 64;
  config.camera.capture.height = 64;
  config.descriptor.bands = 16;
  config.descriptor.rings = 8;
  config.descriptor.longitudes = 32;
  config.capacities.route_frames = 2000;
  const MonotonicClock clock;
  Pipeline pipeline(clock);
  ASSERT_TRUE(pipeline.Init(config).ok());

  sim::StreetOptions street;
  street.width = 64;
  street.height = 64;
  street.seed = 3;
  RouteFrames route;
  ASSERT_TRUE(route.Allocate(2000, static_cast<std::size_t>(pipeline.dim())).ok());
  {
    street.frames = 2000;
    sim::FilmedStreet teach_filmed(street);
    drivers::Camera& teach = teach_filmed.camera;
    ASSERT_TRUE(teach.Open().ok());
    ASSERT_TRUE(teach.Start().ok());
    for (Result<drivers::Frame> f = teach.Capture(std::chrono::seconds(1)); f.ok();
         f = teach.Capture(std::chrono::seconds(1))) {
      FrameResult r;
      ASSERT_TRUE(pipeline.Describe(f->image, &r).ok());
      ASSERT_TRUE(route.Append({}, pipeline.descriptor()));
    }
  }
  ASSERT_TRUE(pipeline.SetRoute(route).ok());

  street.frames = 0;
  sim::FilmedStreet filmed(street);
  drivers::Camera& camera = filmed.camera;
  ASSERT_TRUE(camera.Open().ok());
  ASSERT_TRUE(camera.Start().ok());
  drivers::SimulatedStatusOutput status({}, &clock);
  ASSERT_TRUE(status.Open().ok());
  std::FILE* null = std::fopen("/dev/null", "w");
  ASSERT_NE(null, nullptr);
  drivers::FileLinesOutput lines(null);
  drivers::LocalisationOutput* outputs[] = {&lines};
  OutputPublisher json;
  ASSERT_TRUE(json.Start(outputs, nullptr, 0, PublishMode::kWaitWhenFull).ok());
  LoopOptions options;
  options.max_frames = 2000;
  LoopSummary summary;
  ASSERT_TRUE(RunFrameLoop(camera, &status, pipeline, nullptr, &json, options, &summary).ok());
  Result<std::size_t> before = ResidentSetBytes();
  ASSERT_TRUE(before.ok());

  options.max_frames = 100000;
  AllocationScope scope;
  ASSERT_TRUE(RunFrameLoop(camera, &status, pipeline, nullptr, &json, options, &summary).ok());
  json.Stop();
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(summary.frames, 100000u);
  Result<std::size_t> after = ResidentSetBytes();
  ASSERT_TRUE(after.ok());
  RecordProperty("rss_before_kb", static_cast<int>(*before / 1024));
  RecordProperty("rss_after_kb", static_cast<int>(*after / 1024));
  // A few pages of slack for the stack and libc touching pages for the first time (about
  // 64 KiB seen); a leak of even 4 bytes a frame would add 400 KiB.
  EXPECT_LE(*after, *before + 256 * 1024) << "RSS grew from " << *before << " to " << *after;
  std::fclose(null);
}

}  // namespace
}  // namespace skyloc::firmware
