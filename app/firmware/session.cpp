#include "firmware/session.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <vector>

#include "firmware/button_teach.h"
#include "firmware/output_publisher.h"
#include "firmware/session_drivers.h"
#include "firmware/session_lines.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/localisation_output.h"
#include "skyloc/dsp/place_metrics.h"
#include "skyloc/platform/realtime.h"
#include "skyloc/platform/signals.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/world.h"

namespace skyloc::firmware {
namespace {

// Keeps every frame's result (replay and the demo evaluate them at the end). Storage is
// allocated before the loop; a full recorder drops further frames and counts them.
class ResultRecorder final : public FrameSink {
 public:
  Status Allocate(std::size_t capacity) { return results_.Allocate(capacity); }
  void OnFrame(LoopMode, const FrameResult& r, std::uint64_t) override {
    if (size_ < results_.size())
      results_[size_++] = r;
    else
      ++dropped_;
  }
  std::span<const FrameResult> results() const { return {results_.data(), size_}; }
  std::uint64_t dropped() const { return dropped_; }

 private:
  FixedArray<FrameResult> results_;
  std::size_t size_ = 0;
  std::uint64_t dropped_ = 0;
};

// Horizontal: the session's tolerance is a place on the ground, whatever the camera height
// of either run. A route frame without a pose is NaN, never near anything.
dsp::Position3 GroundPosition(const RouteFrameMeta& meta) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  return meta.pose ? dsp::Position3{meta.pose->x_m, meta.pose->y_m, 0}
                   : dsp::Position3{nan, nan, 0};
}

// Precision/recall of the recorded matches, with ground truth from the poses by the rule of
// dsp/place_metrics.h in distance mode: a query frame farther than the tolerance from the
// whole route is off it; a match is correct when the matched route frame is within the
// tolerance.
void Evaluate(std::span<const FrameResult> results, const RouteFrames& route, double tolerance,
              SessionReport* report) {
  // After the loop: allocation is fine here.
  if (results.empty() || !results.front().has_pose)
    return;  // no ground truth
  std::vector<dsp::Position3> reference(route.size());
  bool route_has_poses = false;
  for (std::size_t i = 0; i < route.size(); ++i) {
    reference[i] = GroundPosition(route.meta(i));
    route_has_poses = route_has_poses || route.meta(i).pose.has_value();
  }
  if (!route_has_poses) {
    report->route_without_poses = true;
    return;
  }
  const dsp::MatchTolerance rule{0, tolerance};
  std::vector<dsp::EvaluatedMatch> matches;
  for (const FrameResult& r : results) {
    if (!r.has_pose)
      return;  // no ground truth
    const dsp::Position3 query{r.pose.x_m, r.pose.y_m, 0};
    dsp::TruthInterval truth;
    dsp::GroundTruthFromPositions(reference, std::span<const dsp::Position3>(&query, 1), tolerance,
                                  std::span<dsp::TruthInterval>(&truth, 1));
    ++report->frames_with_poses;
    report->frames_with_truth += truth.has_truth() ? 1u : 0u;
    const bool known_frame =
        r.best_index >= 0 && static_cast<std::uint64_t>(r.best_index) < reference.size();
    const bool correct =
        r.matched && known_frame &&
        dsp::MatchIsCorrect(static_cast<int>(r.best_index), truth, rule, reference, query);
    if (r.state == dsp::LocalisationState::kLocalised) {
      ++report->localised_frames;
      report->localised_correct += correct ? 1 : 0;
    }
    if (!r.matched)
      continue;
    matches.push_back({r.uniqueness, truth.has_truth(), correct});
  }
  if (matches.empty())
    return;
  const dsp::PrSummary pr = dsp::EvaluatePrecisionRecall(matches).summary;
  report->evaluated = true;
  report->precision_at_full_recall = pr.precision_at_full_recall;
  report->recall_at_full_precision = pr.recall_at_full_precision;
  report->area_under_curve = pr.area_under_curve;
  report->evaluated_matches = pr.evaluated;
  report->correct_matches = pr.correct;
}

// Everything one run holds, from start-up to shut-down; each stage fills or uses its part.
struct Session {
  Session(const SessionArgs& a, const Config& c) : args(a), config(c), label(a.label) {}

  const SessionArgs& args;
  Config config;  // the camera's real size and a dataset's lens filled in at start-up
  const char* label;
  CameraSource source;
  drivers::Camera* camera = nullptr;
  // One clock for the run: the pipeline's stages, the frame loop (through the pipeline),
  // the simulated status output and its button's edges.
  MonotonicClock clock;
  Pipeline pipeline{clock};
  AttitudeParts attitude;
  RouteFrames route;     // repeat: the loaded route's frames (time and pose)
  RouteDbWriter writer;  // teach
  // repeat (live, not replay) with a teach button: a press teaches a new route
  // (button_teach.h), so a missing or empty route is something to wait for, not an error.
  bool teach_button = false;
  std::unique_ptr<drivers::StatusOutput> status;
  ResultRecorder results;
  bool evaluate = false;  // results are kept for the evaluation at the end
  // [output]: the open outputs, in `outputs`, fed by the publisher's thread.
  std::unique_ptr<drivers::FileLinesOutput> stdout_output;
  std::unique_ptr<drivers::UnixSocketOutput> socket_output;
  std::unique_ptr<drivers::LocalisationOutput> dds_output;
  std::vector<drivers::LocalisationOutput*> outputs;
  OutputPublisher publisher;
  DeviceReport devices;  // every device's counters: SIGUSR1, the exit, the JSON lines
  std::unique_ptr<TeeSink> outer, sink;
  FrameRecorder recorder;  // --record
  LoopOptions loop;
  bool capped = false;  // teach stops at the route's capacity
};

// The camera first: its real frame size is what the pipeline is built for.
Status OpenCamera(Session* s) {
  SKYLOC_TRY(MakeCamera(s->config, s->args, &s->source));
  s->camera = s->source.camera.get();
  const drivers::CameraInfo& info = s->camera->info();
  CameraConfig& cam = s->config.camera;
  if (cam.kind == CameraKind::kSim || !s->args.dataset.empty() ||
      cam.kind == CameraKind::kDataset) {
    cam.capture.width = info.width;  // a recorded or simulated source fixes the size
    cam.capture.height = info.height;
    // A dataset recorded with its camera file: use that lens unless the config names one.
    if (cam.lens_file.empty() && !s->source.camera_file.empty()) {
      cam.lens_file = s->source.camera_file;
      cam.lens_file_from_dataset = true;
    }
  } else if (info.width != cam.capture.width || info.height != cam.capture.height) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "camera %s delivers %dx%d, [camera] asks for %dx%d: set width and "
                         "height to what the camera supports",
                         info.name, info.width, info.height, cam.capture.width, cam.capture.height);
  }
  return Status::Ok();
}

// repeat: the route database into the pipeline (the descriptors and strips, held once at
// the matcher's storage type) and `route` (each frame's time and pose, for the truth).
Status LoadRoute(Session* s) {
  const SessionArgs& args = s->args;
  Pipeline& pipeline = s->pipeline;
  SKYLOC_TRY(s->route.Allocate(static_cast<std::size_t>(s->config.capacities.route_frames),
                               static_cast<std::size_t>(pipeline.dim()),
                               pipeline.strip_settings().columns, pipeline.route_sink()));
  RouteDbLoadReport loaded;
  const RouteDbSettings want = pipeline.route_settings();
  struct stat st {};
  const bool missing = ::lstat(args.route_path.c_str(), &st) != 0 && errno == ENOENT;
  if (!(s->teach_button && missing)) {
    SKYLOC_TRY(LoadRouteDb(args.route_path.c_str(), &want, RouteDbLoadPolicy::kStrict, &s->route,
                           &loaded));
  }
  if (s->teach_button && s->route.size() == 0) {
    std::fprintf(stderr,
                 "%s: route %s %s: waiting for the teach button (line %d): press it to "
                 "start teaching, press again to commit the route and repeat on it\n",
                 s->label, args.route_path.c_str(),
                 missing ? "does not exist yet" : "has no frames", s->config.status.button_line);
  } else if (s->route.size() == 0) {
    return Status::Error(StatusCode::kFailedPrecondition, "route %s has no frames: teach it again",
                         args.route_path.c_str());
  }
  if (s->route.size() > 0)
    SKYLOC_TRY(pipeline.SetRoute(s->route));
  // One note, at start-up: a route without strips still localises, without heading.
  if (pipeline.strip_settings().columns != 0 && !pipeline.heading_enabled()) {
    if (loaded.version < 4)
      std::fprintf(stderr,
                   "%s: route %s has no horizon strips (format v%u): heading is off; "
                   "re-teach to get heading\n",
                   s->label, args.route_path.c_str(), loaded.version);
    else
      std::fprintf(stderr,
                   "%s: route %s was taught with [heading] strip_columns = 0: heading is "
                   "off; re-teach to get heading\n",
                   s->label, args.route_path.c_str());
  }
  return Status::Ok();
}

Status OpenStatusOutput(Session* s) {
  SKYLOC_TRY_ASSIGN(s->status, MakeStatusOutput(s->config, &s->clock));
  if (s->status) {
    if (Status open = s->status->Open(); !open.ok()) {
      return open.AddContext("[status] kind = \"%s\", chip = \"%s\"", NameOf(s->config.status.kind),
                             s->config.status.chip.c_str());
    }
  }
  return Status::Ok();
}

// teach: the route database is created after everything else started, so a start-up
// failure leaves no empty route behind (and an existing one untouched).
Status CreateRoute(Session* s) {
  const SessionArgs& args = s->args;
  Status created =
      s->writer.Create(args.route_path.c_str(), s->pipeline.route_settings(),
                       static_cast<std::size_t>(s->config.route_db.flush_every), args.force);
  if (created.code() == StatusCode::kAlreadyExists)
    return Status::Error(created.code(), "%s; pass --force to replace it", created.message());
  SKYLOC_TRY(created);
  PrintReplacedTmp(s->label, args.route_path.c_str(), s->writer.replaced_tmp());
  if (s->writer.replacing()) {
    std::fprintf(stderr,
                 "%s: replacing route %s when this teach commits; until then the old route "
                 "is kept and the frames go to %s\n",
                 s->label, args.route_path.c_str(), s->writer.write_path());
  }
  return Status::Ok();
}

// --record: the recording's folder is created last, after everything else could start.
Status OpenRecording(Session* s) {
  FrameRecorderOptions ro;
  ro.dir = s->args.record_dir;
  ro.with_attitude = s->attitude.source != nullptr && s->pipeline.uses_attitude();
  Result<std::string> camera_toml =
      drivers::CameraFileText(s->pipeline.lens(),
                              "Written by skyloc when it recorded this run: the camera's lens "
                              "(docs/CAMERA_FILE.md).");
  if (camera_toml.ok())
    ro.camera_toml = *camera_toml;
  else
    PrintWarning(s->label,
                 Status(camera_toml.status()).AddContext("no camera.toml in %s", ro.dir.c_str()));
  SKYLOC_TRY(s->recorder.Open(ro, s->camera->info()).AddContext("--record %s", ro.dir.c_str()));
  std::fprintf(stderr, "%s: recording every frame%s into %s\n", s->label,
               ro.with_attitude ? " and its roll/pitch" : "", ro.dir.c_str());
  return Status::Ok();
}

// [output]: the JSON lines on stdout (unless the caller wants none), the socket, DDS. Opened
// before the loop; an output that cannot open is fatal, naming its key.
Status OpenOutputs(Session* s) {
  const OutputConfig& o = s->config.output;
  if (o.to_stdout && s->args.json != nullptr) {
    s->stdout_output = std::make_unique<drivers::FileLinesOutput>(s->args.json);
    s->outputs.push_back(s->stdout_output.get());
  }
  if (o.to_socket) {
    drivers::UnixSocketOutputConfig c;
    std::snprintf(c.path, sizeof c.path, "%s", o.socket_path.c_str());
    c.max_readers = o.socket_max_readers;
    s->socket_output = std::make_unique<drivers::UnixSocketOutput>(c);
    SKYLOC_TRY(s->socket_output->Open().AddContext("[output] socket_path"));
    s->outputs.push_back(s->socket_output.get());
    std::fprintf(stderr, "%s: output socket %s (up to %d readers)\n", s->label, c.path,
                 c.max_readers);
  }
  if (o.to_dds) {
    SKYLOC_TRY_ASSIGN(s->dds_output, MakeDdsOutput(o));
    SKYLOC_TRY(s->dds_output->Open().AddContext("[output] kinds = \"dds\""));
    s->outputs.push_back(s->dds_output.get());
    std::fprintf(stderr, "%s: output dds: ROS 2 topic %s (DDS rt%s), domain %d, /diagnostics\n",
                 s->label, o.ros_topic.c_str(), o.ros_topic.c_str(), o.ros_domain_id);
  }
  return Status::Ok();
}

// Where the frames' results go: the outputs, the caller's sink and, for a finite run
// (a dataset, a simulated trajectory, --frames) the evaluation at the end, which needs the
// poses those sources have. Not with the teach button: the routes change under the results.
Status ConnectSinks(Session* s) {
  std::size_t run_frames = s->source.frames;
  if (s->args.max_frames > 0 && (run_frames == 0 || s->args.max_frames < run_frames))
    run_frames = static_cast<std::size_t>(s->args.max_frames);
  s->evaluate = s->args.mode == LoopMode::kRepeat && run_frames > 0 && !s->teach_button;
  if (s->evaluate)
    SKYLOC_TRY(s->results.Allocate(run_frames));
  // The outputs are published off the frame loop, on the publisher's thread. A real camera
  // does not wait: a full queue drops. A recording or a simulated run has no deadline, and
  // every one of its lines is wanted (tests and scripts count them): the loop waits for
  // room.
  const bool live = s->args.dataset.empty() && (s->config.camera.kind == CameraKind::kV4l2 ||
                                                s->config.camera.kind == CameraKind::kLibcamera);
  const PublishMode mode = live ? PublishMode::kDropWhenFull : PublishMode::kWaitWhenFull;
  if (!s->outputs.empty()) {
    SKYLOC_TRY(
        s->publisher.Start(s->outputs, s->args.mode == LoopMode::kRepeat ? &s->route : nullptr,
                           static_cast<std::size_t>(s->config.capacities.route_frames), mode));
  }
  s->outer =
      std::make_unique<TeeSink>(s->outputs.empty() ? nullptr : &s->publisher, s->args.extra_sink);
  s->sink = std::make_unique<TeeSink>(s->outer.get(), s->evaluate ? &s->results : nullptr);
  return Status::Ok();
}

// Real-time set-up last before the loop: mlockall(MCL_FUTURE) then covers nothing new.
void ApplyRealtimeConfig(const Session& s) {
  RealtimeOptions rt;
  rt.sched_fifo_priority = s.config.realtime.sched_fifo_priority;
  rt.lock_memory = s.config.realtime.mlockall;
  rt.cpu = s.config.realtime.cpu_affinity;
  const RealtimeReport report = ApplyRealtime(rt);
  PrintWarning(s.label, report.scheduling);
  PrintWarning(s.label, report.memory_lock);
  PrintWarning(s.label, report.affinity);
}

// Start-up: camera, pipeline, attitude, route, status output, route writer, the start-up
// line, the result sinks, real time, recording, the camera's stream; all at their
// configured sizes. An error
// returns at once: the parts opened so far close as the session goes.
Status StartUp(Session* s, SessionReport* report) {
  const SessionArgs& args = s->args;
  SKYLOC_TRY(InstallSignalHandlers());
  SKYLOC_TRY(OpenCamera(s));
  SKYLOC_TRY(s->pipeline.Init(s->config));
  SKYLOC_TRY(MakeAttitudeSource(s->config, s->source, &s->attitude));
  s->teach_button = args.mode == LoopMode::kRepeat && args.dataset.empty() &&
                    s->config.status.button_line >= 0 &&
                    s->config.status.kind != StatusOutputKind::kNone;
  if (args.mode == LoopMode::kRepeat) {
    SKYLOC_TRY(LoadRoute(s));
    report->route_frames = s->route.size();
  }
  SKYLOC_TRY(OpenStatusOutput(s));
  if (!args.record_dir.empty()) {
    // Before the route: a recording refused now must leave no route file behind.
    Status recordable = drivers::CheckNewDatasetFolder(args.record_dir);
    if (!recordable.ok())
      return recordable.AddContext("--record %s", args.record_dir.c_str());
  }
  if (args.mode == LoopMode::kTeach)
    SKYLOC_TRY(CreateRoute(s));
  PrintStartup(args, s->config, s->camera->info(), s->writer, s->route.size());
  s->devices.camera = s->camera;
  s->devices.imu = s->attitude.imu.get();
  s->devices.status = s->status.get();
  s->publisher.set_devices(&s->devices);
  s->loop.devices = &s->devices;
  SKYLOC_TRY(OpenOutputs(s));
  SKYLOC_TRY(ConnectSinks(s));
  ApplyRealtimeConfig(*s);
  if (!args.record_dir.empty())
    SKYLOC_TRY(OpenRecording(s));
  return s->camera->Start();
}

// The loop: frames until a signal, the end of the source, --frames or a full route; with
// the teach button, repeat and teach by turns. Returns the loop's own error.
Status RunLoop(Session* s, SessionReport* report) {
  const SessionArgs& args = s->args;
  LoopOptions& loop = s->loop;
  loop.mode = args.mode;
  loop.recorder = s->recorder.is_open() ? &s->recorder : nullptr;
  loop.max_frames = args.max_frames;
  // Teach stops when the route is as long as repeat can load.
  const auto route_capacity = static_cast<std::uint64_t>(s->config.capacities.route_frames);
  s->capped =
      args.mode == LoopMode::kTeach && (loop.max_frames == 0 || loop.max_frames > route_capacity);
  if (s->capped)
    loop.max_frames = route_capacity;
  loop.paced = args.paced;
  loop.recorded = !args.dataset.empty() || s->config.camera.kind == CameraKind::kDataset;
  loop.capture_timeout = std::chrono::milliseconds(s->config.camera.frame_timeout_ms);
  loop.reconnect_timeout = std::chrono::milliseconds(s->config.camera.reconnect_timeout_ms);
  if (!s->teach_button) {
    return RunFrameLoop(*s->camera, s->status.get(), s->pipeline,
                        args.mode == LoopMode::kTeach ? &s->writer : nullptr, s->sink.get(), loop,
                        &report->loop, s->attitude.source.get());
  }
  ButtonDebouncer button(std::chrono::milliseconds(s->config.status.button_debounce_ms));
  ButtonTeachSetup setup;
  setup.camera = s->camera;
  setup.status = s->status.get();
  setup.pipeline = &s->pipeline;
  setup.route = &s->route;
  setup.route_path = args.route_path.c_str();
  setup.flush_every = static_cast<std::size_t>(s->config.route_db.flush_every);
  setup.sink = s->sink.get();
  setup.attitude = s->attitude.source.get();
  setup.label = s->label;
  ButtonTeachReport taught;
  const Status looped = RunRepeatWithButton(setup, loop, &button, &taught);
  report->loop = taught.loop;
  report->route_frames = s->route.size();
  return looped;
}

// The publisher drained and stopped, the outputs closed, what they could not deliver said.
void CloseOutputs(Session* s) {
  s->publisher.Stop();
  const OutputPublisherCounters published = s->publisher.counters();
  if (published.queue_dropped > 0)
    std::fprintf(stderr,
                 "%s: outputs: %llu of %llu frames dropped (the publisher's queue was full)\n",
                 s->label, static_cast<unsigned long long>(published.queue_dropped),
                 static_cast<unsigned long long>(published.frames));
  for (drivers::LocalisationOutput* output : s->outputs) {
    output->Close();
    const drivers::OutputCounters c = output->counters();
    if (output == s->stdout_output.get()) {
      if (c.dropped > 0)
        std::fprintf(stderr, "%s: warning: writing the JSON lines failed (stdout closed?)\n",
                     s->label);
    } else {
      std::fprintf(stderr,
                   "%s: output %s: %llu frames published, %llu deliveries dropped; readers: %llu "
                   "connected, %llu gone, %llu refused\n",
                   s->label, output->name(), static_cast<unsigned long long>(c.published),
                   static_cast<unsigned long long>(c.dropped),
                   static_cast<unsigned long long>(c.readers_seen),
                   static_cast<unsigned long long>(c.readers_gone),
                   static_cast<unsigned long long>(c.readers_refused));
    }
  }
}

// teach: commit what was taught, whatever happened in the loop. Returns the commit's
// error, unless the loop's own (the failed write) already says it.
Status CommitRoute(Session* s, const Status& loop_status, SessionReport* report) {
  const auto route_capacity = static_cast<std::uint64_t>(s->config.capacities.route_frames);
  if (s->capped && report->loop.frames == route_capacity) {
    std::fprintf(stderr,
                 "%s: the route is full ([capacities] route_frames = %llu): raise it to "
                 "teach a longer route\n",
                 s->label, static_cast<unsigned long long>(route_capacity));
  }
  if (s->args.mode != LoopMode::kTeach || !s->writer.is_open())
    return Status::Ok();
  const Status committed = s->writer.Commit();
  report->route_frames = s->writer.frames_durable();
  PrintCommit(s->args, s->writer, committed);
  return loop_status.ok() ? committed : Status::Ok();
}

// Shut-down, whatever happened in the loop: the route committed, the recording closed,
// the lines in their safe state, the devices closed, the counters and latency printed,
// the evaluation. Returns the loop's error first, then the commit's.
Status ShutDown(Session* s, const Status& loop_status, SessionReport* report) {
  const Status committed = CommitRoute(s, loop_status, report);
  if (s->recorder.is_open()) {
    const Status closed = s->recorder.Close();
    PrintRecording(s->label, s->recorder, closed);
  }
  if (s->status) {
    PrintWarning(s->label, s->status->SafeState());
    s->status->Close();
  }
  s->camera->Stop();
  s->camera->Close();
  if (s->attitude.source) {
    PrintAttitude(s->label, *s->attitude.source);
    s->attitude.source->Close();
  }
  CloseOutputs(s);
  s->pipeline.latency().Print(stderr);
  s->devices.Print(stderr);
  if (s->evaluate) {
    // Sized from the run's length, so only a source that delivers more frames than it
    // announced fills it; the evaluation then covers the frames kept, and says so.
    if (s->results.dropped() > 0)
      std::fprintf(stderr,
                   "%s: warning: evaluating the first %zu frames only (%llu more came "
                   "than the run announced)\n",
                   s->label, s->results.results().size(),
                   static_cast<unsigned long long>(s->results.dropped()));
    Evaluate(s->results.results(), s->route, s->args.tolerance_m, report);
  }
  SKYLOC_TRY(loop_status);
  return committed;
}

}  // namespace

int RunSession(const Config& config, const SessionArgs& args, SessionReport* report) {
  SessionReport local;
  if (report == nullptr)
    report = &local;
  Session session(args, config);
  Status s = StartUp(&session, report);
  if (s.ok()) {
    const Status loop_status = RunLoop(&session, report);
    s = ShutDown(&session, loop_status, report);
  }
  if (!s.ok()) {
    report->failure = s.code();
    std::fprintf(stderr, "%s: %s\n", args.label, s.message());
    // What ran before the error is still the user's to know (the frames a teach kept are
    // said by the shut-down itself).
    if (report->loop.frames > 0)
      PrintSummary(args, *report);
    return 1;
  }
  PrintSummary(args, *report);
  return 0;
}

}  // namespace skyloc::firmware
