// The route is held once: a route loaded from the database through
// the pipeline's RouteSink goes straight into the matcher and the heading, and RouteFrames
// keeps only each frame's time and pose. Checked against the same file loaded the other
// way (RouteFrames keeping everything, the pipeline copying it): every repeated frame must
// come out bit for bit the same, and the sunk RouteFrames must hold no descriptor or strip.
#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <vector>

#include "firmware/pipeline.h"
#include "firmware/route_db.h"
#include "skyloc/platform/clock.h"
#include "skyloc/sim/street_source.h"
#include "small_config.h"
#include "support/scratch_dir.h"

namespace skyloc::firmware {
namespace {

using testing::SmallStreet;

// Teaches `frames` frames of the street into a route database file, as teach does.
void TeachFile(Pipeline& pipeline, const std::string& path, std::uint64_t frames) {
  RouteDbWriter writer;
  ASSERT_TRUE(writer.Create(path.c_str(), pipeline.route_settings(), 50, false).ok());
  sim::FilmedStreet filmed(SmallStreet(0, frames));
  ASSERT_TRUE(filmed.camera.Open().ok());
  ASSERT_TRUE(filmed.camera.Start().ok());
  for (Result<drivers::Frame> f = filmed.camera.Capture(std::chrono::seconds(1)); f.ok();
       f = filmed.camera.Capture(std::chrono::seconds(1))) {
    FrameResult r;
    ASSERT_TRUE(pipeline.Describe(f->image, &r).ok());
    RouteFrameMeta meta;
    meta.timestamp_ns = static_cast<std::uint64_t>(f->timestamp.count());
    meta.pose = f->pose;
    ASSERT_TRUE(writer.Append(meta, pipeline.descriptor(), pipeline.strip()).ok());
  }
  ASSERT_TRUE(writer.Commit().ok());
}

TEST(RouteHeldOnce, ALoadThroughThePipelinesSinkMatchesAsACopiedRouteAndKeepsNoDescriptors) {
  skyloc::testing::ScratchDir dir("skyloc_route_once_");
  const std::string path = dir.path() + "/route.db";
  const Config config = testing::SmallConfig();
  const MonotonicClock clock;

  Pipeline copied(clock), sunk(clock);
  ASSERT_TRUE(copied.Init(config).ok());
  ASSERT_TRUE(sunk.Init(config).ok());
  ASSERT_GT(copied.strip_settings().columns, 0u) << "the heading must be on for this test";
  TeachFile(copied, path, 300);

  const auto capacity = static_cast<std::size_t>(config.capacities.route_frames);
  const auto dim = static_cast<std::size_t>(copied.dim());
  const std::size_t columns = copied.strip_settings().columns;
  const RouteDbSettings want = copied.route_settings();
  RouteFrames kept, metas_only;
  ASSERT_TRUE(kept.Allocate(capacity, dim, columns).ok());
  ASSERT_TRUE(metas_only.Allocate(capacity, dim, columns, sunk.route_sink()).ok());
  ASSERT_TRUE(LoadRouteDb(path.c_str(), &want, RouteDbLoadPolicy::kStrict, &kept, nullptr).ok());
  ASSERT_TRUE(
      LoadRouteDb(path.c_str(), &want, RouteDbLoadPolicy::kStrict, &metas_only, nullptr).ok());
  ASSERT_TRUE(copied.SetRoute(kept).ok());
  ASSERT_TRUE(sunk.SetRoute(metas_only).ok());

  // What the sunk RouteFrames holds: the times and poses, no descriptor, no strip.
  ASSERT_EQ(metas_only.size(), 300u);
  ASSERT_EQ(kept.size(), 300u);
  EXPECT_TRUE(metas_only.has_strips());
  for (std::size_t i = 0; i < metas_only.size(); ++i) {
    EXPECT_TRUE(metas_only.descriptor(i).empty()) << i;
    EXPECT_TRUE(metas_only.strip(i).empty()) << i;
    EXPECT_FALSE(kept.descriptor(i).empty()) << i;
    EXPECT_EQ(metas_only.meta(i).timestamp_ns, kept.meta(i).timestamp_ns) << i;
    ASSERT_TRUE(metas_only.meta(i).pose.has_value()) << i;
    EXPECT_EQ(metas_only.meta(i).pose->x_m, kept.meta(i).pose->x_m) << i;
  }
  EXPECT_EQ(sunk.route_size(), copied.route_size());
  EXPECT_TRUE(sunk.heading_enabled());
  EXPECT_TRUE(copied.heading_enabled());

  // Another drive of the street, through both: the same result in every frame.
  sim::FilmedStreet filmed(SmallStreet(1, 250));
  ASSERT_TRUE(filmed.camera.Open().ok());
  ASSERT_TRUE(filmed.camera.Start().ok());
  int frames = 0, localised = 0, with_heading = 0;
  for (Result<drivers::Frame> f = filmed.camera.Capture(std::chrono::seconds(1)); f.ok();
       f = filmed.camera.Capture(std::chrono::seconds(1))) {
    FrameResult a, b;
    ASSERT_TRUE(copied.Localise(*f, &a).ok());
    ASSERT_TRUE(sunk.Localise(*f, &b).ok());
    ++frames;
    EXPECT_EQ(a.best_index, b.best_index) << "frame " << frames;
    EXPECT_EQ(a.confidence, b.confidence) << "frame " << frames;
    EXPECT_EQ(a.state, b.state) << "frame " << frames;
    EXPECT_EQ(a.has_heading, b.has_heading) << "frame " << frames;
    EXPECT_EQ(a.heading_deg, b.heading_deg) << "frame " << frames;
    localised += b.state == dsp::LocalisationState::kLocalised ? 1 : 0;
    with_heading += b.has_heading ? 1 : 0;
  }
  EXPECT_EQ(frames, 250);
  // Not a vacuous comparison: the route localises and the heading runs.
  EXPECT_GT(localised, 100);
  EXPECT_GT(with_heading, 100);
}

}  // namespace
}  // namespace skyloc::firmware
