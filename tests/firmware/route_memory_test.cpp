// What a place of a loaded route costs in memory (docs/BENCHMARKS.md, "Route memory per
// place"): the bytes repeat allocates at start-up for a route's capacity, counted by the
// allocation counter at two capacities, against the sum of the parts the code documents.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>

#include "firmware/config.h"
#include "firmware/output_publisher.h"
#include "firmware/pipeline.h"
#include "firmware/route_db.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/platform/alloc_counter.h"

namespace skyloc::firmware {
namespace {

const MonotonicClock kRouteMemoryClock;

// Start-up bytes of repeat's route-sized parts for a route of `capacity` places: the
// pipeline (its matcher and the route's strips), the route's times and poses, and the
// publisher's distance along the route.
std::uint64_t StartupBytes(Config config, int capacity) {
  config.capacities.route_frames = capacity;
  const AllocationScope scope;
  Pipeline pipeline(kRouteMemoryClock);
  EXPECT_TRUE(pipeline.Init(config).ok());
  RouteFrames route;
  EXPECT_TRUE(route
                  .Allocate(static_cast<std::size_t>(capacity),
                            static_cast<std::size_t>(pipeline.dim()),
                            pipeline.strip_settings().columns, pipeline.route_sink())
                  .ok());
  RouteProgress progress;
  EXPECT_TRUE(progress.Allocate(static_cast<std::size_t>(capacity)).ok());
  return scope.bytes();
}

TEST(RouteMemory, BytesAPlaceAreTheSumOfTheParts) {
  ASSERT_TRUE(AllocationCounterActive());
  Config config = DefaultConfig();   // 120 bands, the route filter
  config.camera.capture.width = 64;  // the camera's tables do not grow with the route
  config.camera.capture.height = 64;
  for (const dsp::ReferenceStorage storage :
       {dsp::ReferenceStorage::kFloat32, dsp::ReferenceStorage::kBFloat16,
        dsp::ReferenceStorage::kCodes16, dsp::ReferenceStorage::kCodes8}) {
    for (const int columns : {0, 180, 360}) {
      config.capacities.route_storage = storage;
      config.heading.strip.n_azimuth = columns;
      const std::uint64_t per_place =
          (StartupBytes(config, 2000) - StartupBytes(config, 1000)) / 1000;
      const std::size_t row = dsp::RouteFilter::BytesPerReference(config.descriptor.bands, storage);
      const std::size_t meta = sizeof(std::uint64_t) + 6 * sizeof(float);  // time, pose
      const std::size_t along = sizeof(double);                            // the publisher's
      // Packed, 4 bits a column (route format 6): a byte minimum, a byte range, the levels.
      const std::size_t strip = columns == 0 ? 0 : 2 + static_cast<std::size_t>(columns) / 2;
      std::printf(
          "%-8s %3d columns: %llu bytes a place = filter row %zu + time and pose %zu + "
          "distance %zu + strip %zu\n",
          dsp::ReferenceStorageName(storage), columns, static_cast<unsigned long long>(per_place),
          row, meta, along, strip);
      EXPECT_EQ(per_place, row + meta + along + strip)
          << dsp::ReferenceStorageName(storage) << ", " << columns << " columns";
    }
  }
}

}  // namespace
}  // namespace skyloc::firmware
