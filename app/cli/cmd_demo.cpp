// The demo: what skyloc does, end to end, on the simulated camera. Teach a route through a
// procedural world, then drive it again tilted, zig-zagging and in different light, with a
// live progress line; end with precision/recall and the per-stage latency table. It runs
// the same session code as `skyloc teach` and `skyloc repeat`.
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "cli/commands.h"
#include "firmware/session.h"

namespace skyloc::cli {
using namespace skyloc::firmware;
namespace {

constexpr const char* kDescription =
    "Teaches a route in a simulated world (a camera at 10 frames a second on a robot that\n"
    "stops on the way), repeats it 1.5x faster with tilt, zig-zag and dawn light, and\n"
    "prints precision/recall and the latency of every stage.\n";

// One line that rewrites itself on a terminal, or a line every 50 frames otherwise.
class ProgressLine final : public FrameSink {
 public:
  explicit ProgressLine(const char* what) : what_(what), tty_(::isatty(STDOUT_FILENO) != 0) {}
  void OnFrame(LoopMode mode, const FrameResult& r, std::uint64_t route_frames) override {
    ++frames_;
    if (!tty_ && frames_ % 50 != 0)
      return;
    if (mode == LoopMode::kTeach) {
      std::printf("%s  %-6s frame %5llu  recorded %5llu  sky %4.0f %%  %5lld us%s",
                  tty_ ? "\r" : "", what_, static_cast<unsigned long long>(r.frame),
                  static_cast<unsigned long long>(route_frames),
                  100.0 * static_cast<double>(r.sky_fraction),
                  static_cast<long long>(r.latency.count() / 1000), tty_ ? "   " : "\n");
    } else {
      char match[24] = "-";
      if (r.matched)
        std::snprintf(match, sizeof match, "%lld", static_cast<long long>(r.best_index));
      std::printf("%s  %-6s frame %5llu  %-9s  confidence %.2f  route frame %5s  %5lld us%s",
                  tty_ ? "\r" : "", what_, static_cast<unsigned long long>(r.frame),
                  dsp::LocalisationStateName(r.state), static_cast<double>(r.confidence), match,
                  static_cast<long long>(r.latency.count() / 1000), tty_ ? "   " : "\n");
    }
    std::fflush(stdout);
  }
  void Finish() {
    if (tty_)
      std::printf("\n");
    std::fflush(stdout);
  }

 private:
  const char* what_;
  bool tty_;
  std::uint64_t frames_ = 0;
};

// The demo's configuration: the built-in defaults with a simulated camera at a fixed
// frame rate on a robot that starts standing, cruises at changing speeds and stops on the
// way (docs/SIMULATOR.md, "Motion"); --quick: small frames, fewer bands, a shorter run.
Config DemoConfig(const char* world, bool quick) {
  Config c = DefaultConfig();
  c.camera.kind = CameraKind::kSim;
  c.camera.sim.name = world;
  c.camera.capture.width = quick ? 96 : 320;
  c.camera.capture.height = quick ? 96 : 240;
  c.camera.capture.fps = 10;
  c.camera.sim.frames.sampling = sim::Sampling::kTime;
  c.camera.sim.frames.speed.cruise_mps = quick ? 3.0 : 2.0;
  c.camera.sim.frames.speed.start_stop_s = 2;
  c.camera.sim.frames.speed.stops = quick ? 1 : 2;
  c.camera.sim.frames.speed.stop_min_s = 2;
  c.camera.sim.frames.speed.stop_max_s = 3;
  if (quick) {
    c.descriptor.bands = 24;
    ResolveDescriptorGrid(&c.descriptor);  // the grid follows the bands
  }
  c.source = "the demo's own settings";
  return c;
}

// One of the demo's two simulated runs (`run`: its mode, route, frames, label and motion),
// with a progress line on the terminal in place of JSON lines.
int RunDemoSession(const Config& config, SessionArgs run, SessionReport* report) {
  ProgressLine progress(run.label);
  run.json = nullptr;
  run.extra_sink = &progress;
  run.simulation_expected = true;
  const int rc = RunSession(config, run, report);
  progress.Finish();
  return rc;
}

struct DemoOptions {
  std::string world = "city";
  bool quick = false;
};

ParseOutcome ParseArgs(std::span<char* const> args, DemoOptions* o) {
  OptionTable t("demo", "[--world city|forest|repetitive] [--quick]", kDescription);
  t.Choice<std::string>("--world", "the procedural world (default city)",
                        {{"city", "city"}, {"forest", "forest"}, {"repetitive", "repetitive"}},
                        &o->world);
  t.Flag("--quick", "a short run on small frames (the test suite's)", &o->quick);
  return t.Parse(args);
}

// Teaches the world's route, repeats it and reports both.
int TeachAndRepeat(const DemoOptions& o) {
  const std::string& world = o.world;
  const bool quick = o.quick;
  // The configuration is built in memory; the taught route is a real route database (teach
  // and repeat run exactly as on the robot), in a folder of its own under $TMPDIR (or
  // /tmp), removed at the end.
  const char* tmp = std::getenv("TMPDIR");
  std::string dir =
      std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/skyloc_demo_XXXXXX";
  if (::mkdtemp(dir.data()) == nullptr) {
    const int saved = errno;
    std::fprintf(stderr,
                 "skyloc demo: cannot create a folder for the route (%s): %s; set TMPDIR to a "
                 "writable folder\n",
                 dir.c_str(), std::strerror(saved));
    return kExitFailure;
  }
  const std::string route_path = std::string(dir) + "/route.db";
  const Config config = DemoConfig(world.c_str(), quick);

  std::printf("skyloc demo: %s world, upward 185-degree fisheye, %s frames\n", world.c_str(),
              quick ? "96x96" : "320x240");
  std::printf(
      "1. teach: drive the route once at noon, 10 frames a second, standing at the start and "
      "stopping on the way, and record its sky descriptors\n");
  SessionReport taught;
  const int teach_rc = RunDemoSession(config,
                                      {.mode = LoopMode::kTeach,
                                       .route_path = route_path,
                                       .max_frames = quick ? 300u : 1200u,
                                       .label = "teach"},
                                      &taught);

  int rc = teach_rc;
  SessionReport repeated;
  if (teach_rc == 0) {
    std::printf(
        "\n2. repeat: drive it again 1.5x faster with its own stops, tilted 10 deg, "
        "zig-zagging +-20 deg, at dawn, with other clouds and noise\n");
    SimRunConfig sim;
    sim.ride.speed_ratio = 1.5;
    sim.ride.tilt_deg = 10;
    sim.ride.zigzag_deg = 20;
    sim.ride.seed = 2;
    sim.lighting = "dawn";
    // Within the stretch the teach run covered (1.5x faster, so fewer frames).
    rc = RunDemoSession(config,
                        {.mode = LoopMode::kRepeat,
                         .route_path = route_path,
                         .max_frames = quick ? 160u : 700u,
                         .label = "repeat",
                         .sim = sim},
                        &repeated);
  }
  if (rc == 0) {
    std::printf("\n3. result: %llu route frames taught, %llu frames repeated\n",
                static_cast<unsigned long long>(taught.route_frames),
                static_cast<unsigned long long>(repeated.loop.frames));
    if (repeated.evaluated) {
      std::printf(
          "   precision at 100%% recall %.2f, recall at 100%% precision %.2f (matched "
          "route frame within 2 m)\n",
          repeated.precision_at_full_recall, repeated.recall_at_full_precision);
      std::printf("   LOCALISED %llu of %llu frames, %llu of them correct\n",
                  static_cast<unsigned long long>(repeated.localised_frames),
                  static_cast<unsigned long long>(repeated.loop.frames),
                  static_cast<unsigned long long>(repeated.localised_correct));
    }
    std::printf("   the per-stage latency tables are above (stderr)\n");
  }
  std::remove(route_path.c_str());
  ::rmdir(dir.c_str());
  return rc == 0 ? kExitOk : kExitFailure;
}

}  // namespace

int RunDemo(std::span<char* const> args) {
  return RunParsed(args, ParseArgs, TeachAndRepeat);
}

}  // namespace skyloc::cli
