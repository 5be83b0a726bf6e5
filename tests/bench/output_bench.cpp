// What a reader of the local socket output costs the frame loop: the loop on the built-in
// street with the socket output on and no reader, then with a reader that connected and
// never reads (its queue full, every send to it refused at once). p99 of the loop's
// per-frame time from the firmware's own latency table, and the second's p99 as a ratio
// of the first's, measured in the same run. The sends happen on the publisher thread, so
// the ratio should stay near 1. Opens a socket: runs only inside
// ../shared/tools/isolated (it says so and skips otherwise).
#include <benchmark/benchmark.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "firmware/frame_loop.h"
#include "firmware/output_publisher.h"
#include "firmware/small_config.h"
#include "skyloc/drivers/localisation_output.h"
#include "skyloc/drivers/simulated_status_output.h"
#include "skyloc/platform/signals.h"
#include "skyloc/sim/street_source.h"
#include "support/network_namespace.h"

namespace {

using namespace skyloc;
using namespace skyloc::firmware;

double g_p99_without_reader_us = 0;

void FrameLoopWithSocket(benchmark::State& state, bool dead_reader) {
  const std::string problem = skyloc::testing::NetworkIsolationProblem();
  if (!problem.empty()) {
    state.SkipWithError(problem.c_str());
    return;
  }
  char dir[] = "/tmp/skyloc-output-bench-XXXXXX";
  if (::mkdtemp(dir) == nullptr) {
    state.SkipWithError("mkdtemp failed");
    return;
  }
  const std::string path = std::string(dir) + "/localisation.sock";
  MonotonicClock clock;
  Pipeline pipeline(clock);
  RouteFrames route;
  bool ok = pipeline.Init(skyloc::firmware::testing::SmallConfig()).ok();
  {
    sim::FilmedStreet taught(skyloc::firmware::testing::SmallStreet(1, 300));
    ok = ok && taught.camera.Open().ok() && taught.camera.Start().ok() &&
         route
             .Allocate(400, static_cast<std::size_t>(pipeline.dim()),
                       pipeline.strip_settings().columns)
             .ok();
    for (Result<drivers::Frame> f = taught.camera.Capture(std::chrono::seconds(1)); ok && f.ok();
         f = taught.camera.Capture(std::chrono::seconds(1))) {
      FrameResult r;
      RouteFrameMeta meta;
      meta.pose = *f->pose;
      ok = pipeline.Describe(f->image, &r).ok() &&
           route.Append(meta, pipeline.descriptor(), pipeline.strip());
    }
  }
  ok = ok && pipeline.SetRoute(route).ok();
  sim::FilmedStreet filmed(skyloc::firmware::testing::SmallStreet(2, 0));
  drivers::SimulatedStatusOutput status({}, &clock);
  drivers::UnixSocketOutputConfig c;
  std::snprintf(c.path, sizeof c.path, "%s", path.c_str());
  drivers::UnixSocketOutput socket(c);
  ok = ok && filmed.camera.Open().ok() && filmed.camera.Start().ok() && status.Open().ok() &&
       socket.Open().ok();
  int reader = -1;
  if (ok && dead_reader) {
    reader = ::socket(AF_UNIX, SOCK_SEQPACKET | SOCK_CLOEXEC, 0);
    sockaddr_un a{};
    a.sun_family = AF_UNIX;
    std::snprintf(a.sun_path, sizeof a.sun_path, "%s", path.c_str());
    ok = ::connect(reader, reinterpret_cast<const sockaddr*>(&a), sizeof a) == 0;
  }
  drivers::LocalisationOutput* outputs[] = {&socket};
  OutputPublisher publisher;
  // A live camera's run: off the frame loop, a full queue drops rather than waits.
  ok = ok && publisher.Start(outputs, &route, route.capacity(), PublishMode::kDropWhenFull).ok();
  if (!ok) {
    state.SkipWithError("set-up failed");
  } else {
    ClearSignalFlags();
    LoopOptions options;
    options.max_frames = 100;
    LoopSummary summary;
    (void)RunFrameLoop(filmed.camera, &status, pipeline, nullptr, &publisher, options, &summary);
    pipeline.latency().Clear();  // the warm-up, and the dead reader's queue filling
    for (auto _ : state) {
      if (!RunFrameLoop(filmed.camera, &status, pipeline, nullptr, &publisher, options, &summary)
               .ok())
        state.SkipWithError("frame loop failed");
    }
    const LatencyHistogram& total = pipeline.latency().stage(pipeline.stages().total);
    const double p99_us = static_cast<double>(total.Percentile(99).count()) / 1000.0;
    state.counters["frames"] = static_cast<double>(total.count());
    state.counters["p50_us"] = static_cast<double>(total.Percentile(50).count()) / 1000.0;
    state.counters["p99_us"] = p99_us;
    if (!dead_reader)
      g_p99_without_reader_us = p99_us;
    else if (g_p99_without_reader_us > 0)
      state.counters["p99_ratio_to_no_reader"] = p99_us / g_p99_without_reader_us;
  }
  publisher.Stop();
  state.counters["socket_dropped"] = static_cast<double>(socket.counters().dropped);
  socket.Close();
  if (reader >= 0)
    ::close(reader);
  ::rmdir(dir);
}

// Registered in this order: the dead reader's ratio is to the first's p99 of this run.
void BM_FrameLoopSocketNoReader(benchmark::State& state) {
  FrameLoopWithSocket(state, false);
}
BENCHMARK(BM_FrameLoopSocketNoReader)->Unit(benchmark::kMillisecond)->MinTime(3.0);

void BM_FrameLoopSocketDeadReader(benchmark::State& state) {
  FrameLoopWithSocket(state, true);
}
BENCHMARK(BM_FrameLoopSocketDeadReader)->Unit(benchmark::kMillisecond)->MinTime(3.0);

}  // namespace
