// One run of the firmware: `skyloc teach`, `skyloc repeat`, `skyloc replay` (and the demo
// calls the same). Start-up opens the camera, builds the pipeline from the configuration
// and opens or loads the route database, all at their configured sizes; then the frame
// loop; then the clean shutdown: the route database flushed and committed, the status
// lines in their safe state, the latency table printed.
#pragma once

#include <cstdint>
#include <cstdio>
#include <string>

#include "firmware/config.h"
#include "firmware/frame_loop.h"

namespace skyloc::firmware {

// Every member has a default, so a caller names only what it sets ({.mode = ..., ...}).
struct SessionArgs {
  LoopMode mode = LoopMode::kRepeat;
  std::string route_path{};
  // --config: the command reads it (LoadConfigFile) and hands RunSession the Config;
  // empty: the built-in defaults (config/skyloc.toml's values).
  std::string config_path{};
  std::string dataset{};  // replay: frames from this dataset folder
  bool paced = false;     // replay at the recorded pace
  bool force = false;     // teach: replace an existing route database
  // The demo: a simulated camera and status output are the point, not a mistake to warn of.
  bool simulation_expected = false;
  std::uint64_t max_frames = 0;
  std::FILE* json = stdout;  // one line per frame; null for none
  FrameSink* extra_sink = nullptr;
  double tolerance_m = 2.0;  // replay/demo: a match within this distance is correct
  // --record DIR (teach, repeat) and `skyloc record DIR`: the frames into this dataset folder.
  std::string record_dir{};
  const char* label = "skyloc";
  // camera.kind = "sim": how this run moves and what the light is like (the world and
  // its sampling come from the configuration: ConfiguredSimRun, sim_run.h).
  SimRunConfig sim{};
};

struct SessionReport {
  StatusCode failure = StatusCode::kOk;  // why the run failed (its message went to stderr)
  LoopSummary loop;
  std::uint64_t route_frames = 0;  // recorded (teach) or loaded (repeat, replay)
  bool evaluated = false;          // replay/demo with poses: precision/recall below
  double precision_at_full_recall = 0;
  double recall_at_full_precision = 0;
  double area_under_curve = 0;
  int evaluated_matches = 0;
  int correct_matches = 0;
  // Frames shown LOCALISED whose match was correct, of those shown LOCALISED.
  std::uint64_t localised_frames = 0;
  std::uint64_t localised_correct = 0;
  // The frames had poses but the route has none (taught from a recording without them):
  // no match can be checked, so there is no precision/recall rather than a false 0.
  bool route_without_poses = false;
  // Frames with poses, and those of them on the route (within the tolerance of a route
  // pose): only those have a ground truth.
  std::uint64_t frames_with_poses = 0;
  std::uint64_t frames_with_truth = 0;
};

// Runs `config` (a file's, the built-in defaults or one built in memory, as the demo's).
// Returns the exit code; errors are printed to stderr as "label: message".
int RunSession(const Config& config, const SessionArgs& args, SessionReport* report = nullptr);

}  // namespace skyloc::firmware
