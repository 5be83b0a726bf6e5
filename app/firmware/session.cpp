#include "firmware/session.h"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>

#include "skyloc/drivers/attitude_source.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/iio_imu.h"
#include "skyloc/drivers/simulated_camera.h"
#include "skyloc/drivers/simulated_imu.h"
#include "skyloc/drivers/simulated_status_output.h"
#if SKYLOC_WITH_V4L2
#include "skyloc/drivers/v4l2_camera.h"
#endif
#if SKYLOC_WITH_LIBCAMERA
#include "skyloc/drivers/libcamera_camera.h"
#endif
#if SKYLOC_WITH_GPIOD
#include "skyloc/drivers/gpio_status_output.h"
#endif
#include "firmware/button_teach.h"
#include "skyloc/dsp/place_metrics.h"
#include "skyloc/platform/realtime.h"
#include "skyloc/platform/signals.h"
#include "skyloc/sim/imu_model.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/rendered_source.h"
#include "skyloc/sim/street_source.h"
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
  std::vector<dsp::Position3> reference(route.size());
  for (std::size_t i = 0; i < route.size(); ++i)
    reference[i] = GroundPosition(route.meta(i));
  const dsp::MatchTolerance rule{0, tolerance};
  std::vector<dsp::EvaluatedMatch> matches;
  for (const FrameResult& r : results) {
    if (!r.has_pose)
      return;  // no ground truth
    const dsp::Position3 query{r.pose.x_m, r.pose.y_m, 0};
    dsp::TruthInterval truth;
    dsp::GroundTruthFromPositions(reference, std::span<const dsp::Position3>(&query, 1), tolerance,
                                  std::span<dsp::TruthInterval>(&truth, 1));
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

// The frame source and what it needs to stay alive (a simulated world and trajectory).
struct CameraSource {
  std::unique_ptr<sim::World> world;
  std::vector<sim::TrajectoryPoint> trajectory;
  MonotonicClock clock;                              // a simulated camera's
  std::unique_ptr<drivers::FrameSource> sim_source;  // what a simulated camera films
  std::unique_ptr<drivers::Camera> camera;
  std::size_t frames = 0;   // a finite source's length; 0 = endless
  std::string camera_file;  // a dataset's own camera.toml, if it has one
  bool dataset_has_attitude = false;
  std::uint64_t run_seed = 0;  // a simulated run's seed (its IMU's noise and bias)
};

// [attitude]: the source of the robot's roll and pitch, opened (an IMU found and started).
struct AttitudeParts {
  std::vector<dsp::ImuSample> sim_samples;  // kind = sim: the simulated IMU's readings
  std::unique_ptr<drivers::ImuDevice> imu;
  std::unique_ptr<drivers::AttitudeSource> source;
};

Status MakeAttitudeSource(const Config& config, const CameraSource& camera, AttitudeParts* out) {
  const AttitudeConfig& a = config.attitude;
  const drivers::ImuMounting mounting{a.mount_roll_deg, a.mount_pitch_deg, a.mount_yaw_deg};
  drivers::ImuAttitudeConfig imu_config;
  imu_config.filter.kp = a.filter_kp;
  imu_config.filter.ki = a.filter_ki;
  imu_config.filter.accel_gate_mps2 = a.accel_gate_mps2;
  imu_config.stale = std::chrono::milliseconds(a.stale_ms);
  switch (a.kind) {
    case AttitudeKind::kNone:
      return Status::Ok();
    case AttitudeKind::kDataset:
      if (!camera.dataset_has_attitude)
        return Status::Error(StatusCode::kFailedPrecondition,
                             "[attitude] kind = \"dataset\": the dataset has no roll_deg,pitch_deg "
                             "columns (docs/DATASETS.md): record it with its attitude, or set "
                             "[attitude] kind = \"none\"");
      out->source = std::make_unique<drivers::FrameAttitudeSource>();
      break;
    case AttitudeKind::kSim: {
      if (camera.trajectory.empty())
        return Status::Error(StatusCode::kFailedPrecondition,
                             "[attitude] kind = \"sim\" needs a simulated run with a trajectory "
                             "([camera] kind = \"sim\", sim_world city, forest or repetitive)");
      sim::ImuModelConfig model;
      model.rate_hz = a.rate_hz;
      model.seed = sim::ImuSeedForRun(camera.run_seed);
      SKYLOC_TRY(sim::SimulateImu(camera.trajectory, model, &out->sim_samples));
      drivers::SimulatedImuConfig c;
      c.sample_rate_hz = a.rate_hz;
      // The simulator's IMU reads in the robot's body frame, which the simulated lens's
      // mount makes the descriptor's: [attitude] mount angles rotate it further, as they
      // would a real IMU's.
      out->imu = std::make_unique<drivers::SimulatedImu>(c, out->sim_samples, nullptr, mounting);
      out->source = std::make_unique<drivers::ImuAttitudeSource>(out->imu.get(), imu_config);
      break;
    }
    case AttitudeKind::kIio: {
      drivers::IioImuConfig c;
      std::snprintf(c.device, sizeof c.device, "%s", a.device.c_str());
      std::snprintf(c.gyro_device, sizeof c.gyro_device, "%s", a.gyro_device.c_str());
      std::snprintf(c.trigger, sizeof c.trigger, "%s", a.trigger.c_str());
      c.sample_rate_hz = a.rate_hz;
      c.mounting = mounting;
      out->imu = std::make_unique<drivers::IioImu>(c);
      out->source = std::make_unique<drivers::ImuAttitudeSource>(out->imu.get(), imu_config);
      break;
    }
  }
  if (Status s = out->source->Open(); !s.ok()) {
    return s.AddContext("[attitude] kind = \"%s\"%s%s%s", AttitudeKindName(a.kind),
                        a.kind == AttitudeKind::kIio ? ", device = \"" : "",
                        a.kind == AttitudeKind::kIio ? a.device.c_str() : "",
                        a.kind == AttitudeKind::kIio ? "\"" : "");
  }
  return Status::Ok();
}

Status MakeSimSource(const Config& config, const SimRun& run, CameraSource* source) {
  if (config.camera.sim_world == "street") {
    sim::StreetOptions o;
    o.width = config.camera.width;
    o.height = config.camera.height;
    o.seed = static_cast<std::uint64_t>(config.camera.sim_seed);
    o.fps = config.camera.fps;
    o.paced = true;  // a live run: frames come at the camera's rate
    o.step_m = run.spacing_m;
    o.speed_jitter = std::min(run.speed_jitter, 0.5);
    o.tilt_deg = run.tilt_deg;
    o.zigzag_deg = run.zigzag_deg;
    o.brightness = run.lighting == "dawn" ? 0.6 : run.lighting == "overcast" ? 0.8 : 1.0;
    auto street = std::make_unique<sim::StreetSource>(o);
    source->camera = std::make_unique<drivers::SimulatedCamera>(street->camera_config(),
                                                                street.get(), &source->clock);
    source->sim_source = std::move(street);
    return Status::Ok();
  }
  sim::WorldKind kind{};
  if (!sim::ParseWorldKind(config.camera.sim_world.c_str(), &kind))
    return Status::Error(StatusCode::kInvalidArgument, "[camera] sim_world \"%s\" is unknown",
                         config.camera.sim_world.c_str());
  source->world = std::make_unique<sim::World>();
  SKYLOC_TRY(sim::MakeProceduralWorld(kind, static_cast<std::uint64_t>(config.camera.sim_seed),
                                      source->world.get()));
  sim::MotionConfig motion;
  motion.frame_spacing_m = run.spacing_m;
  motion.speed_jitter = run.speed_jitter;
  motion.height_m = run.camera_height_m;
  motion.tilt_deg = run.tilt_deg;
  motion.zigzag_deg = run.zigzag_deg;
  motion.bumps_deg = run.bumps_deg;
  motion.yaw_offset_deg = run.yaw_deg;
  motion.fps = config.camera.fps;
  if (config.camera.sim_sampling == "time") {
    motion.sampling = sim::Sampling::kTime;
    motion.speed.cruise_mps = config.camera.sim_speed_mps;
    motion.speed.band = config.camera.sim_speed_band;
    motion.speed.accel_mps2 = config.camera.sim_accel_mps2;
    motion.speed.start_stop_s = config.camera.sim_start_stop_s;
    motion.speed.stops = config.camera.sim_stops;
    motion.speed.stop_min_s = config.camera.sim_stop_min_s;
    motion.speed.stop_max_s = config.camera.sim_stop_max_s;
    motion.speed_ratio = run.speed_ratio;
  }
  motion.seed = run.run_seed;
  source->run_seed = run.run_seed;
  SKYLOC_TRY(sim::BuildTrajectory(source->world->route, source->world->route_closed, motion,
                                  &source->trajectory));
  sim::RenderedSourceConfig camera;
  SKYLOC_TRY_ASSIGN(camera.lens, LensFromConfig(config));
  if (!sim::LightingPreset(run.lighting.c_str(), run.run_seed, &camera.lighting))
    return Status::Error(StatusCode::kInvalidArgument,
                         "lighting \"%s\" is not dawn, noon or "
                         "overcast",
                         run.lighting.c_str());
  auto rendered =
      std::make_unique<sim::RenderedSource>(source->world.get(), source->trajectory, camera);
  source->camera = std::make_unique<drivers::SimulatedCamera>(rendered->camera_config(),
                                                              rendered.get(), &source->clock);
  source->sim_source = std::move(rendered);
  source->frames = source->trajectory.size();
  return Status::Ok();
}

Status MakeCamera(const Config& config, const SessionArgs& args, CameraSource* source) {
  if (!args.dataset.empty() || config.camera.kind == CameraKind::kDataset) {
    auto camera = std::make_unique<drivers::DatasetCamera>(
        args.dataset.empty() ? config.camera.dataset : args.dataset);
    SKYLOC_TRY(camera->Open());
    source->frames = camera->dataset().frames.size();
    source->camera_file = camera->dataset().camera_toml;
    source->dataset_has_attitude = camera->dataset().has_attitude;
    source->camera = std::move(camera);
    return Status::Ok();
  }
  switch (config.camera.kind) {
    case CameraKind::kSim:
      SKYLOC_TRY(MakeSimSource(config, args.sim, source));
      return source->camera->Open();
    case CameraKind::kV4l2: {
#if SKYLOC_WITH_V4L2
      drivers::V4l2CameraConfig c;
      std::snprintf(c.device, sizeof c.device, "%s", config.camera.device.c_str());
      c.width = config.camera.width;
      c.height = config.camera.height;
      c.fps = config.camera.fps;
      source->camera = std::make_unique<drivers::V4l2Camera>(c);
      return source->camera->Open();
#else
      break;
#endif
    }
    case CameraKind::kLibcamera: {
#if SKYLOC_WITH_LIBCAMERA
      drivers::LibcameraCameraConfig c;
      std::snprintf(c.camera_id, sizeof c.camera_id, "%s",
                    config.camera.device == "/dev/video0" ? "" : config.camera.device.c_str());
      c.width = config.camera.width;
      c.height = config.camera.height;
      source->camera = std::make_unique<drivers::LibcameraCamera>(c);
      return source->camera->Open();
#else
      break;
#endif
    }
    case CameraKind::kDataset:
      break;
  }
  return Status::Error(StatusCode::kUnimplemented,
                       "[camera] kind = \"%s\": this skyloc was built without that driver (its "
                       "development package was missing at build time); use \"sim\" or "
                       "\"dataset\", or rebuild",
                       CameraKindName(config.camera.kind));
}

drivers::StatusLineMode LineMode(const Config& config) {
  return config.status.encoding == StatusEncoding::kBlink ? drivers::StatusLineMode::kBlink
                                                          : drivers::StatusLineMode::kLinePerState;
}

Result<std::unique_ptr<drivers::StatusOutput>> MakeStatusOutput(const Config& config,
                                                                const Clock* clock) {
  switch (config.status.kind) {
    case StatusOutputKind::kNone:
      return std::unique_ptr<drivers::StatusOutput>();
    case StatusOutputKind::kSim: {
      drivers::SimulatedStatusOutputConfig c;
      c.mode = LineMode(config);
      c.has_button = config.status.button_line >= 0;
      return std::unique_ptr<drivers::StatusOutput>(
          std::make_unique<drivers::SimulatedStatusOutput>(c, clock));
    }
    case StatusOutputKind::kGpio: {
#if SKYLOC_WITH_GPIOD
      drivers::GpioStatusOutputConfig c;
      std::snprintf(c.chip, sizeof c.chip, "%s", config.status.chip.c_str());
      c.mode = LineMode(config);
      c.active_low = config.status.active_low;
      c.button_line = config.status.button_line;
      c.button_active_low = config.status.button_active_low;
      // Per state: LOST, SEARCHING, LOCALISED; blinking uses the LOCALISED line.
      if (c.mode == drivers::StatusLineMode::kBlink) {
        c.lines = {static_cast<unsigned>(config.status.line_localised), 0u, 0u};
      } else {
        c.lines = {static_cast<unsigned>(config.status.line_lost),
                   static_cast<unsigned>(config.status.line_searching),
                   static_cast<unsigned>(config.status.line_localised)};
      }
      return std::unique_ptr<drivers::StatusOutput>(std::make_unique<drivers::GpioStatusOutput>(c));
#else
      break;
#endif
    }
  }
  return Status::Error(StatusCode::kUnimplemented,
                       "[status] kind = \"gpio\": this skyloc was built without libgpiod "
                       "(libgpiod-dev was missing at build time); use \"sim\" or \"none\"");
}

// The one start-up line: what the run reads, shows and writes, so a simulated or wrong
// device cannot go unnoticed; then a loud warning for a live mode on a simulation.
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
                  "camera sim (SIMULATED world \"%s\", seed %lld), %s %dx%d @ %g fps",
                  cam.sim_world.c_str(), static_cast<long long>(cam.sim_seed), format, info.width,
                  info.height, cam.fps);
  } else {
    std::snprintf(
        camera, sizeof camera, "camera %s %s, %s %dx%d @ %g fps", CameraKindName(cam.kind),
        cam.kind == CameraKind::kLibcamera && cam.device == "/dev/video0" ? "(the first camera)"
                                                                          : cam.device.c_str(),
        format, info.width, info.height, cam.fps);
  }
  char status[200];
  switch (config.status.kind) {
    case StatusOutputKind::kGpio:
      if (config.status.encoding == StatusEncoding::kBlink)
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

// Everything after the configuration is read. Errors return; RunSession prints them.
Status Run(const SessionArgs& args, Config config, SessionReport* report) {
  const char* label = args.label;
  SKYLOC_TRY(InstallSignalHandlers());

  // The camera first: its real frame size is what the pipeline is built for.
  CameraSource source;
  SKYLOC_TRY(MakeCamera(config, args, &source));
  drivers::Camera* camera = source.camera.get();
  const drivers::CameraInfo& info = camera->info();
  if (config.camera.kind == CameraKind::kSim || !args.dataset.empty() ||
      config.camera.kind == CameraKind::kDataset) {
    config.camera.width = info.width;  // a recorded or simulated source fixes the size
    config.camera.height = info.height;
    // A dataset recorded with its camera file: use that lens unless the config names one.
    if (config.camera.lens_file.empty() && !source.camera_file.empty()) {
      config.camera.lens_file = source.camera_file;
      config.camera.lens_file_from_dataset = true;
    }
  } else if (info.width != config.camera.width || info.height != config.camera.height) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "camera %s delivers %dx%d, [camera] asks for %dx%d: set width and "
                         "height to what the camera supports",
                         info.name, info.width, info.height, config.camera.width,
                         config.camera.height);
  }

  // One clock for the run: the pipeline's stages, the frame loop (through the pipeline),
  // the simulated status output and its button's edges.
  MonotonicClock clock;
  Pipeline pipeline(clock);
  SKYLOC_TRY(pipeline.Init(config));
  AttitudeParts attitude;
  SKYLOC_TRY(MakeAttitudeSource(config, source, &attitude));

  RouteDbWriter writer;
  RouteFrames route;
  // repeat (live, not replay) with a teach button: a press teaches a new route
  // (button_teach.h), so a missing or empty route is something to wait for, not an error.
  const bool teach_button = args.mode == LoopMode::kRepeat && args.dataset.empty() &&
                            config.status.button_line >= 0 &&
                            config.status.kind != StatusOutputKind::kNone;
  if (args.mode == LoopMode::kRepeat) {
    // The descriptors and strips go straight to the pipeline (held once, at the matcher's
    // storage type); `route` keeps each frame's time and pose for the replay's truth.
    SKYLOC_TRY(route.Allocate(static_cast<std::size_t>(config.capacities.route_frames),
                              static_cast<std::size_t>(pipeline.dim()),
                              pipeline.strip_settings().columns, pipeline.route_sink()));
    RouteDbLoadReport loaded;
    const RouteDbSettings want = pipeline.route_settings();
    struct stat st {};
    const bool missing = ::lstat(args.route_path.c_str(), &st) != 0 && errno == ENOENT;
    if (!(teach_button && missing)) {
      SKYLOC_TRY(
          LoadRouteDb(args.route_path.c_str(), &want, RouteDbLoadPolicy::kStrict, &route, &loaded));
    }
    if (teach_button && route.size() == 0) {
      std::fprintf(stderr,
                   "%s: route %s %s: waiting for the teach button (line %d): press it to "
                   "start teaching, press again to commit the route and repeat on it\n",
                   label, args.route_path.c_str(), missing ? "does not exist yet" : "has no frames",
                   config.status.button_line);
    } else if (route.size() == 0) {
      return Status::Error(StatusCode::kFailedPrecondition,
                           "route %s has no frames: teach it "
                           "again",
                           args.route_path.c_str());
    }
    if (route.size() > 0)
      SKYLOC_TRY(pipeline.SetRoute(route));
    report->route_frames = route.size();
    // One note, at start-up: a route without strips still localises, without heading.
    if (pipeline.strip_settings().columns != 0 && !pipeline.heading_enabled()) {
      if (loaded.version < 4)
        std::fprintf(stderr,
                     "%s: route %s has no horizon strips (format v%u): heading is off; "
                     "re-teach to get heading\n",
                     args.label, args.route_path.c_str(), loaded.version);
      else
        std::fprintf(stderr,
                     "%s: route %s was taught with [heading] strip_columns = 0: heading is "
                     "off; re-teach to get heading\n",
                     args.label, args.route_path.c_str());
    }
  }

  SKYLOC_TRY_ASSIGN(std::unique_ptr<drivers::StatusOutput> status,
                    MakeStatusOutput(config, &clock));
  if (status) {
    if (Status open = status->Open(); !open.ok()) {
      return open.AddContext("[status] kind = \"%s\", chip = \"%s\"",
                             StatusOutputKindName(config.status.kind), config.status.chip.c_str());
    }
  }
  // The route database is created last, so a start-up failure leaves no empty route
  // behind (and an existing one untouched).
  if (args.mode == LoopMode::kTeach) {
    Status created =
        writer.Create(args.route_path.c_str(), pipeline.route_settings(),
                      static_cast<std::size_t>(config.route_db.flush_every), args.force);
    if (!args.force && std::strstr(created.message(), "already exists") != nullptr)  // problem, fix
      created = Status::Error(created.code(), "%s; pass --force to replace it", created.message());
    SKYLOC_TRY(created);
    if (writer.replacing()) {
      std::fprintf(stderr,
                   "%s: replacing route %s when this teach commits; until then the old route "
                   "is kept and the frames go to %s\n",
                   label, args.route_path.c_str(), writer.write_path());
    }
  }

  PrintStartup(args, config, info, writer, route.size());

  ResultRecorder recorder;
  // A finite run (a dataset, a simulated trajectory, --frames) keeps every result for the
  // evaluation at the end; it needs poses, which those sources have.
  std::size_t run_frames = source.frames;
  if (args.max_frames > 0 && (run_frames == 0 || args.max_frames < run_frames))
    run_frames = static_cast<std::size_t>(args.max_frames);
  // (Not with the teach button: the routes change under the results.)
  const bool evaluate = args.mode == LoopMode::kRepeat && run_frames > 0 && !teach_button;
  if (evaluate)
    SKYLOC_TRY(recorder.Allocate(run_frames));
  JsonLinesSink json(args.json);
  TeeSink outer(args.json != nullptr ? &json : nullptr, args.extra_sink);
  TeeSink sink(&outer, evaluate ? &recorder : nullptr);

  // Real-time setup last: mlockall(MCL_FUTURE) then covers nothing new.
  RealtimeOptions rt;
  rt.sched_fifo_priority = config.realtime.sched_fifo_priority;
  rt.lock_memory = config.realtime.mlockall;
  rt.cpu = config.realtime.cpu_affinity;
  const RealtimeReport rt_report = ApplyRealtime(rt);
  PrintWarning(label, rt_report.scheduling);
  PrintWarning(label, rt_report.memory_lock);
  PrintWarning(label, rt_report.affinity);

  // The recording: its folder is created last, after everything else could start.
  FrameRecorder frame_recorder;
  if (!args.record_dir.empty()) {
    FrameRecorderOptions ro;
    ro.dir = args.record_dir;
    ro.with_attitude = attitude.source != nullptr && pipeline.uses_attitude();
    Result<std::string> camera_toml =
        drivers::CameraFileText(pipeline.lens(),
                                "Written by skyloc when it recorded this run: the camera's lens "
                                "(docs/CAMERA_FILE.md).");
    if (camera_toml.ok())
      ro.camera_toml = *camera_toml;
    else
      PrintWarning(label,
                   Status(camera_toml.status()).AddContext("no camera.toml in %s", ro.dir.c_str()));
    SKYLOC_TRY(frame_recorder.Open(ro, info).AddContext("--record %s", ro.dir.c_str()));
    std::fprintf(stderr, "%s: recording every frame%s into %s\n", label,
                 ro.with_attitude ? " and its roll/pitch" : "", ro.dir.c_str());
  }

  SKYLOC_TRY(camera->Start());
  LoopOptions loop;
  loop.mode = args.mode;
  loop.recorder = frame_recorder.is_open() ? &frame_recorder : nullptr;
  loop.max_frames = args.max_frames;
  // Teach stops when the route is as long as repeat can load.
  const auto route_capacity = static_cast<std::uint64_t>(config.capacities.route_frames);
  const bool capped =
      args.mode == LoopMode::kTeach && (loop.max_frames == 0 || loop.max_frames > route_capacity);
  if (capped)
    loop.max_frames = route_capacity;
  loop.paced = args.paced;
  loop.recorded = !args.dataset.empty() || config.camera.kind == CameraKind::kDataset;
  loop.capture_timeout = std::chrono::milliseconds(config.camera.frame_timeout_ms);
  loop.reconnect_timeout = std::chrono::milliseconds(config.camera.reconnect_timeout_ms);
  Status loop_status;
  if (teach_button) {
    ButtonDebouncer button(std::chrono::milliseconds(config.status.button_debounce_ms));
    ButtonTeachSetup setup;
    setup.camera = camera;
    setup.status = status.get();
    setup.pipeline = &pipeline;
    setup.route = &route;
    setup.route_path = args.route_path.c_str();
    setup.flush_every = static_cast<std::size_t>(config.route_db.flush_every);
    setup.sink = &sink;
    setup.attitude = attitude.source.get();
    setup.label = label;
    ButtonTeachReport taught;
    loop_status = RunRepeatWithButton(setup, loop, &button, &taught);
    report->loop = taught.loop;
    report->route_frames = route.size();
  } else {
    loop_status = RunFrameLoop(*camera, status.get(), pipeline,
                               args.mode == LoopMode::kTeach ? &writer : nullptr, &sink, loop,
                               &report->loop, attitude.source.get());
  }

  if (capped && report->loop.frames == route_capacity) {
    std::fprintf(stderr,
                 "%s: the route is full ([capacities] route_frames = %llu): raise it to "
                 "teach a longer route\n",
                 label, static_cast<unsigned long long>(route_capacity));
  }
  // Shutdown, whatever happened in the loop: keep what was taught, lines to safe state.
  Status shutdown;
  if (args.mode == LoopMode::kTeach && writer.is_open()) {
    shutdown = writer.Commit();
    report->route_frames = writer.frames_durable();
    const auto kept = static_cast<unsigned long long>(writer.frames_durable());
    if (shutdown.ok()) {
      std::fprintf(stderr, "%s: route %s: %llu frames committed\n", label, args.route_path.c_str(),
                   kept);
    } else if (writer.committed()) {
      // Disk full: what was on the disk is committed, the last chunk is not.
      std::fprintf(stderr,
                   "%s: route %s: %llu frames kept and committed; the last %llu did not fit: "
                   "%s\n",
                   label, args.route_path.c_str(), kept,
                   static_cast<unsigned long long>(writer.frames_lost()), shutdown.message());
    } else {
      // The fix depends on why: a full disk needs space, anything else (EIO: a failing card
      // or cable) needs the storage looked at first.
      const int e = shutdown.sys_errno();
      const bool full = e == ENOSPC || e == EFBIG || e == EDQUOT;
      std::fprintf(stderr,
                   "%s: route %s: %llu frames kept on the disk but NOT committed (%s): %s, "
                   "then run 'skyloc route recover %s'\n",
                   label, writer.write_path(), kept, shutdown.message(),
                   full ? "free some space" : "check the storage (dmesg shows the device's errors)",
                   writer.write_path());
    }
    // The loop's own error (the failed write) is printed at the end; this was said.
    if (!shutdown.ok() && !loop_status.ok())
      shutdown = Status::Ok();
  }
  if (frame_recorder.is_open()) {
    const Status closed = frame_recorder.Close();
    const FrameRecorderCounters c = frame_recorder.counters();
    std::fprintf(stderr,
                 "%s: recording %s: %llu frames written, %llu dropped (the disk slower than the "
                 "camera)%s%s\n",
                 label, frame_recorder.dir().c_str(), static_cast<unsigned long long>(c.written),
                 static_cast<unsigned long long>(c.dropped),
                 closed.ok() ? "" : "; stopped: ", closed.ok() ? "" : closed.message());
    if (c.without_attitude > 0)
      std::fprintf(stderr, "%s: recording: %llu frames had no attitude (written as level)\n", label,
                   static_cast<unsigned long long>(c.without_attitude));
  }
  if (status) {
    PrintWarning(label, status->SafeState());
    status->Close();
  }
  camera->Stop();
  camera->Close();
  if (attitude.source) {
    const drivers::AttitudeCounters& c = attitude.source->counters();
    std::fprintf(stderr,
                 "%s: attitude %s: %llu frames with an attitude, %llu described as level "
                 "(%llu none or stale, %llu source gone)\n",
                 label, attitude.source->name(), static_cast<unsigned long long>(c.estimates),
                 static_cast<unsigned long long>(c.missing + c.unavailable),
                 static_cast<unsigned long long>(c.missing),
                 static_cast<unsigned long long>(c.unavailable));
    attitude.source->Close();
  }
  pipeline.latency().Print(stderr);
  if (json.write_failed())
    std::fprintf(stderr, "%s: warning: writing the JSON lines failed (stdout closed?)\n", label);
  if (evaluate) {
    // Sized from the run's length, so only a source that delivers more frames than it
    // announced fills it; the evaluation then covers the frames kept, and says so.
    if (recorder.dropped() > 0)
      std::fprintf(stderr,
                   "%s: warning: evaluating the first %zu frames only (%llu more came "
                   "than the run announced)\n",
                   label, recorder.results().size(),
                   static_cast<unsigned long long>(recorder.dropped()));
    Evaluate(recorder.results(), route, args.tolerance_m, report);
  }
  SKYLOC_TRY(loop_status);
  return shutdown;
}

// The run's closing lines on stderr: frames by state and capture errors, and the
// evaluation when there was one.
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
  if (r.evaluated) {
    std::fprintf(stderr,
                 "%s: precision at 100%% recall %.3f, recall at 100%% precision %.3f, AUC %.3f "
                 "(%d matches, %d correct within %.1f m); LOCALISED frames correct: %llu of "
                 "%llu\n",
                 args.label, r.precision_at_full_recall, r.recall_at_full_precision,
                 r.area_under_curve, r.evaluated_matches, r.correct_matches, args.tolerance_m,
                 static_cast<unsigned long long>(r.localised_correct),
                 static_cast<unsigned long long>(r.localised_frames));
  }
}

}  // namespace

int RunSession(const SessionArgs& args, SessionReport* report) {
  SessionReport local;
  if (report == nullptr)
    report = &local;
  Config config = DefaultConfig();
  if (!args.config_path.empty()) {
    Result<Config> loaded = LoadConfigFile(args.config_path.c_str());
    if (!loaded.ok()) {
      std::fprintf(stderr, "%s: %s\n", args.label, loaded.status().message());
      return 1;
    }
    config = *loaded;
  }
  const Status s = Run(args, config, report);
  if (!s.ok()) {
    std::fprintf(stderr, "%s: %s\n", args.label, s.message());
    // What ran before the error is still the user's to know (the frames a teach kept are
    // said by Run itself).
    if (report->loop.frames > 0)
      PrintSummary(args, *report);
    return 1;
  }
  PrintSummary(args, *report);
  return 0;
}

}  // namespace skyloc::firmware
