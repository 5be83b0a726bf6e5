#include "firmware/session_lines.h"

#include <cerrno>
#include <cstdio>
#include <cstring>

namespace skyloc::firmware {

void PrintStartup(const SessionArgs& args, const Config& config, const drivers::CameraInfo& info,
                  const RouteDbWriter& writer, std::size_t loaded_frames) {
  const CameraConfig& cam = config.camera;
  const bool dataset = !args.dataset.empty() || cam.kind == CameraKind::kDataset;
  char camera[400];
  const char* format = dsp::PixelFormatName(info.format);
  if (dataset) {
    std::snprintf(camera, sizeof camera, "camera dataset %s (recorded), %s %dx%d",
                  args.dataset.empty() ? cam.dataset.c_str() : args.dataset.c_str(), format,
                  info.width, info.height);
  } else if (cam.kind == CameraKind::kSim) {
    std::snprintf(camera, sizeof camera,
                  "camera sim (SIMULATED world \"%s\", seed %llu), %s %dx%d @ %g fps",
                  cam.sim.name.c_str(), static_cast<unsigned long long>(cam.sim.seed), format,
                  info.width, info.height, cam.capture.fps);
  } else {
    std::snprintf(camera, sizeof camera, "camera %s %s, %s %dx%d @ %g fps", NameOf(cam.kind),
                  cam.kind == CameraKind::kLibcamera && cam.device == "/dev/video0"
                      ? "(the first camera)"
                      : cam.device.c_str(),
                  format, info.width, info.height, cam.capture.fps);
  }
  char status[200];
  switch (config.status.kind) {
    case StatusOutputKind::kGpio:
      if (config.status.encoding == drivers::StatusLineMode::kBlink)
        std::snprintf(status, sizeof status, "status gpio %s line %d (blink)",
                      config.status.chip.c_str(), config.status.line_localised);
      else
        std::snprintf(status, sizeof status, "status gpio %s lines %d/%d/%d (per-state)",
                      config.status.chip.c_str(), config.status.line_lost,
                      config.status.line_searching, config.status.line_localised);
      break;
    case StatusOutputKind::kSim:
      std::snprintf(status, sizeof status, "status sim (SIMULATED, no GPIO line)");
      break;
    case StatusOutputKind::kNone:
      std::snprintf(status, sizeof status, "status none");
      break;
  }
  if (config.status.button_line >= 0 && config.status.kind != StatusOutputKind::kNone) {
    const std::size_t used = std::strlen(status);
    std::snprintf(status + used, sizeof status - used, ", teach button line %d%s",
                  config.status.button_line,
                  config.status.button_active_low ? " (active-low)" : "");
  }
  char route[80];
  if (args.mode == LoopMode::kRepeat && loaded_frames == 0)
    std::snprintf(route, sizeof route, "none yet: the teach button teaches it");
  else if (args.mode == LoopMode::kTeach)
    std::snprintf(route, sizeof route, "%s", writer.replacing() ? "replacing it at commit" : "new");
  else
    std::snprintf(route, sizeof route, "%zu frames", loaded_frames);
  if (args.mode == LoopMode::kRecord) {
    std::fprintf(stderr, "%s: %s; %s; recording into %s; config %s\n", args.label, camera, status,
                 args.record_dir.c_str(),
                 config.source.empty() ? "built-in defaults" : config.source.c_str());
  } else {
    std::fprintf(stderr, "%s: %s; %s; route %s (%s); config %s\n", args.label, camera, status,
                 args.route_path.c_str(), route,
                 config.source.empty() ? "built-in defaults" : config.source.c_str());
  }

  if (args.simulation_expected || dataset)
    return;
  const char* from = config.source.empty() ? "the built-in defaults" : config.source.c_str();
  if (cam.kind == CameraKind::kSim) {
    std::fprintf(stderr,
                 "%s: WARNING: the camera is SIMULATED ([camera] kind = \"sim\" in %s): this %s "
                 "uses a rendered world, not what the robot sees; set [camera] kind = \"v4l2\" "
                 "or \"libcamera\"\n",
                 args.label, from,
                 args.mode == LoopMode::kTeach    ? "teach"
                 : args.mode == LoopMode::kRecord ? "recording"
                                                  : "repeat");
  }
  if (args.mode == LoopMode::kRepeat && config.status.kind == StatusOutputKind::kSim) {
    std::fprintf(stderr,
                 "%s: WARNING: the status output is SIMULATED ([status] kind = \"sim\" in %s): "
                 "no GPIO line will change; set [status] kind = \"gpio\"\n",
                 args.label, from);
  }
}

void PrintWarning(const char* label, const Status& s) {
  if (!s.ok())
    std::fprintf(stderr, "%s: warning: %s\n", label, s.message());
}

void PrintReplacedTmp(const char* label, const char* route_path, const RouteTmpReport& tmp) {
  if (!tmp.exists)
    return;
  if (tmp.loads)
    std::fprintf(stderr,
                 "%s: replacing %s.tmp, left by an interrupted teach (%zu intact frames, never "
                 "committed)\n",
                 label, route_path, tmp.frames);
  else
    std::fprintf(stderr,
                 "%s: replacing %s.tmp, left by an interrupted teach (%llu bytes, no intact "
                 "frame)\n",
                 label, route_path, static_cast<unsigned long long>(tmp.bytes));
}

void PrintCommit(const SessionArgs& args, const RouteDbWriter& writer, const Status& committed) {
  const char* label = args.label;
  const auto kept = static_cast<unsigned long long>(writer.frames_durable());
  if (writer.discarded()) {
    // Nothing reached the disk: the path is as the teach found it.
    std::fprintf(
        stderr, "%s: route %s: no frame committed%s%s%s; %s\n", label, args.route_path.c_str(),
        committed.ok() ? "" : " (", committed.ok() ? "" : committed.message(),
        committed.ok() ? "" : ")",
        writer.replacing() ? "the old route is kept as it was" : "no route file was left behind");
    return;
  }
  if (committed.ok()) {
    std::fprintf(stderr, "%s: route %s: %llu frames committed\n", label, args.route_path.c_str(),
                 kept);
  } else if (writer.committed()) {
    // Disk full: what was on the disk is committed, the last chunk is not.
    std::fprintf(stderr,
                 "%s: route %s: %llu frames kept and committed; the last %llu did not fit: "
                 "%s\n",
                 label, args.route_path.c_str(), kept,
                 static_cast<unsigned long long>(writer.frames_lost()), committed.message());
  } else {
    // The fix depends on why: a full disk needs space, anything else (EIO: a failing card
    // or cable) needs the storage looked at first.
    const int e = committed.sys_errno();
    const bool full = e == ENOSPC || e == EFBIG || e == EDQUOT;
    std::fprintf(stderr,
                 "%s: route %s: %llu frames kept on the disk but NOT committed (%s): %s, "
                 "then run 'skyloc route recover %s'\n",
                 label, writer.write_path(), kept, committed.message(),
                 full ? "free some space" : "check the storage (dmesg shows the device's errors)",
                 writer.write_path());
  }
}

void PrintRecording(const char* label, const FrameRecorder& recorder, const Status& closed) {
  const FrameRecorderCounters c = recorder.counters();
  std::fprintf(stderr,
               "%s: recording %s: %llu frames written, %llu dropped (the disk slower than the "
               "camera)%s%s\n",
               label, recorder.dir().c_str(), static_cast<unsigned long long>(c.written),
               static_cast<unsigned long long>(c.dropped),
               closed.ok() ? "" : "; stopped: ", closed.ok() ? "" : closed.message());
  if (c.without_attitude > 0)
    std::fprintf(stderr, "%s: recording: %llu frames had no attitude (written as level)\n", label,
                 static_cast<unsigned long long>(c.without_attitude));
}

void PrintAttitude(const char* label, const drivers::AttitudeSource& source) {
  const drivers::AttitudeCounters& c = source.counters();
  std::fprintf(stderr,
               "%s: attitude %s: %llu frames with an attitude, %llu described as level "
               "(%llu none or stale, %llu source gone)\n",
               label, source.name(), static_cast<unsigned long long>(c.estimates),
               static_cast<unsigned long long>(c.missing + c.unavailable),
               static_cast<unsigned long long>(c.missing),
               static_cast<unsigned long long>(c.unavailable));
}

void PrintSummary(const SessionArgs& args, const SessionReport& r) {
  if (args.mode == LoopMode::kRecord) {
    std::fprintf(stderr, "%s: %llu frames captured, %llu capture errors%s\n", args.label,
                 static_cast<unsigned long long>(r.loop.frames),
                 static_cast<unsigned long long>(r.loop.capture_errors),
                 r.loop.stopped ? ", stopped by signal" : "");
    return;
  }
  std::fprintf(stderr,
               "%s: %llu frames (%llu LOST, %llu SEARCHING, %llu LOCALISED), %llu capture "
               "errors%s\n",
               args.label, static_cast<unsigned long long>(r.loop.frames),
               static_cast<unsigned long long>(r.loop.state_frames[0]),
               static_cast<unsigned long long>(r.loop.state_frames[1]),
               static_cast<unsigned long long>(r.loop.state_frames[2]),
               static_cast<unsigned long long>(r.loop.capture_errors),
               r.loop.stopped ? ", stopped by signal" : "");
  if (r.loop.frames_without_contrast > 0)
    std::fprintf(stderr,
                 "%s: %llu frames showed no sky (no contrast between sky and ground: lens cap "
                 "on, sensor saturated or fogged?); they were not matched\n",
                 args.label, static_cast<unsigned long long>(r.loop.frames_without_contrast));
  if (r.evaluated) {
    std::fprintf(stderr,
                 "%s: precision at 100%% recall %.3f, recall at 100%% precision %.3f, AUC %.3f "
                 "(%d matches, %d correct within %.1f m); LOCALISED frames correct: %llu of "
                 "%llu\n",
                 args.label, r.precision_at_full_recall, r.recall_at_full_precision,
                 r.area_under_curve, r.evaluated_matches, r.correct_matches, args.tolerance_m,
                 static_cast<unsigned long long>(r.localised_correct),
                 static_cast<unsigned long long>(r.localised_frames));
    // Frames off the route have no truth and count in no score: scores over a few of them
    // say little, so the coverage is told whenever it is not whole.
    if (r.frames_with_truth < r.frames_with_poses)
      std::fprintf(stderr,
                   "%s: %s: the ground truth covers %llu of %llu frames (the others are "
                   "farther than %.1f m from every route pose and are not scored)\n",
                   args.label, 2 * r.frames_with_truth < r.frames_with_poses ? "warning" : "note",
                   static_cast<unsigned long long>(r.frames_with_truth),
                   static_cast<unsigned long long>(r.frames_with_poses), args.tolerance_m);
  }
  if (r.route_without_poses)
    std::fprintf(stderr,
                 "%s: no precision/recall: route %s has no poses (taught from a recording "
                 "without them), so no match can be checked; teach from a run with poses to "
                 "score repeat\n",
                 args.label, args.route_path.c_str());
}

}  // namespace skyloc::firmware
