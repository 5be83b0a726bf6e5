#include "firmware/session_drivers.h"

#include <algorithm>
#include <chrono>
#include <cstdio>

#include "skyloc/drivers/dataset.h"
#if SKYLOC_WITH_DDS
#include "skyloc/drivers/dds_output.h"
#endif
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
#include "firmware/pipeline.h"
#include "firmware/sim_run.h"
#include "skyloc/sim/imu_model.h"
#include "skyloc/sim/rendered_source.h"
#include "skyloc/sim/street_source.h"

namespace skyloc::firmware {
namespace {

// A simulated camera: the configured world with the command line's run, rendered (or the
// street world's frames), its trajectory kept for a simulated IMU.
Status MakeSimSource(const Config& config, const SimRunConfig& command_line, CameraSource* source) {
  const SimRunConfig run = ConfiguredSimRun(config.camera.sim, command_line);
  if (run.world.name == "street") {
    sim::StreetOptions o;
    o.width = config.camera.capture.width;
    o.height = config.camera.capture.height;
    o.seed = run.world.seed;
    o.fps = config.camera.capture.fps;
    o.paced = true;  // a live run: frames come at the camera's rate
    o.step_m = run.world.frames.frame_spacing_m;
    o.speed_jitter = std::min(run.world.frames.speed_jitter, 0.5);
    o.tilt_deg = run.ride.tilt_deg;
    o.zigzag_deg = run.ride.zigzag_deg;
    o.brightness = run.lighting == "dawn" ? 0.6 : run.lighting == "overcast" ? 0.8 : 1.0;
    auto street = std::make_unique<sim::StreetSource>(o);
    source->camera = std::make_unique<drivers::SimulatedCamera>(street->camera_config(),
                                                                street.get(), &source->clock);
    source->sim_source = std::move(street);
    return Status::Ok();
  }
  sim::WorldKind kind{};
  if (!sim::ParseWorldKind(run.world.name.c_str(), &kind))
    return Status::Error(StatusCode::kInvalidArgument, "[camera] sim_world \"%s\" is unknown",
                         run.world.name.c_str());
  source->world = std::make_unique<sim::World>();
  SKYLOC_TRY(sim::MakeProceduralWorld(kind, run.world.seed, source->world.get()));
  const sim::MotionConfig motion = SimMotionConfig(run, config.camera.capture.fps);
  source->run_seed = run.ride.seed;
  SKYLOC_TRY(sim::BuildTrajectory(source->world->route, source->world->route_closed, motion,
                                  &source->trajectory));
  sim::RenderedSourceConfig camera;
  SKYLOC_TRY_ASSIGN(camera.lens, LensFromConfig(config));
  SKYLOC_TRY_ASSIGN(camera.lighting, SimLighting(run));
  auto rendered =
      std::make_unique<sim::RenderedSource>(source->world.get(), source->trajectory, camera);
  source->camera = std::make_unique<drivers::SimulatedCamera>(rendered->camera_config(),
                                                              rendered.get(), &source->clock);
  source->sim_source = std::move(rendered);
  source->frames = source->trajectory.size();
  return Status::Ok();
}

// A live camera, not yet opened: its driver's config is the device and the capture format
// of [camera] (libcamera's camera id is the device key, the default device meaning the
// first camera).
Result<std::unique_ptr<drivers::Camera>> MakeLiveCamera(
    [[maybe_unused]] const CameraConfig& camera) {
#if SKYLOC_WITH_V4L2
  if (camera.kind == CameraKind::kV4l2) {
    drivers::V4l2CameraConfig c;
    std::snprintf(c.device, sizeof c.device, "%s", camera.device.c_str());
    c.capture = camera.capture;
    return std::unique_ptr<drivers::Camera>(std::make_unique<drivers::V4l2Camera>(c));
  }
#endif
#if SKYLOC_WITH_LIBCAMERA
  if (camera.kind == CameraKind::kLibcamera) {
    drivers::LibcameraCameraConfig c;
    const bool first_camera = camera.device == "/dev/video0";
    std::snprintf(c.camera_id, sizeof c.camera_id, "%s", first_camera ? "" : camera.device.c_str());
    c.capture = camera.capture;
    return std::unique_ptr<drivers::Camera>(std::make_unique<drivers::LibcameraCamera>(c));
  }
#endif
  return Status::Error(StatusCode::kUnimplemented,
                       "[camera] kind = \"%s\": this skyloc was built without that driver (its "
                       "development package was missing at build time); use \"sim\" or "
                       "\"dataset\", or rebuild",
                       NameOf(camera.kind));
}

}  // namespace

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
    return s.AddContext("[attitude] kind = \"%s\"%s%s%s", NameOf(a.kind),
                        a.kind == AttitudeKind::kIio ? ", device = \"" : "",
                        a.kind == AttitudeKind::kIio ? a.device.c_str() : "",
                        a.kind == AttitudeKind::kIio ? "\"" : "");
  }
  return Status::Ok();
}

Status MakeCamera(const Config& config, const SessionArgs& args, CameraSource* source) {
  if (!args.dataset.empty() || config.camera.kind == CameraKind::kDataset) {
    auto camera = std::make_unique<drivers::DatasetCamera>(
        args.dataset.empty() ? config.camera.dataset : args.dataset);
    if (args.dataset.empty())
      SKYLOC_TRY(
          CheckPathKey(config, "[camera] dataset", config.camera.dataset, PathKind::kFolder));
    SKYLOC_TRY(camera->Open());
    source->frames = camera->dataset().frames.size();
    source->camera_file = camera->dataset().camera_toml;
    source->dataset_has_attitude = camera->dataset().has_attitude;
    source->camera = std::move(camera);
    return Status::Ok();
  }
  if (config.camera.kind == CameraKind::kSim) {
    SKYLOC_TRY(MakeSimSource(config, args.sim, source));
  } else {
    SKYLOC_TRY_ASSIGN(source->camera, MakeLiveCamera(config.camera));
  }
  return source->camera->Open();
}

Result<std::unique_ptr<drivers::StatusOutput>> MakeStatusOutput(const Config& config,
                                                                const Clock* clock) {
  switch (config.status.kind) {
    case StatusOutputKind::kNone:
      return std::unique_ptr<drivers::StatusOutput>();
    case StatusOutputKind::kSim: {
      drivers::SimulatedStatusOutputConfig c;
      c.mode = config.status.encoding;
      c.has_button = config.status.button_line >= 0;
      return std::unique_ptr<drivers::StatusOutput>(
          std::make_unique<drivers::SimulatedStatusOutput>(c, clock));
    }
    case StatusOutputKind::kGpio: {
#if SKYLOC_WITH_GPIOD
      drivers::GpioStatusOutputConfig c;
      std::snprintf(c.chip, sizeof c.chip, "%s", config.status.chip.c_str());
      c.mode = config.status.encoding;
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

Result<std::unique_ptr<drivers::LocalisationOutput>> MakeDdsOutput(const OutputConfig& o) {
#if SKYLOC_WITH_DDS
  drivers::DdsOutputConfig c;
  std::snprintf(c.topic, sizeof c.topic, "rt%s", o.ros_topic.c_str());
  std::snprintf(c.frame_id, sizeof c.frame_id, "%s", o.frame_id.c_str());
  c.domain_id = o.ros_domain_id;
  return std::unique_ptr<drivers::LocalisationOutput>(std::make_unique<drivers::DdsOutput>(c));
#else
  (void)o;
  return Status::Error(StatusCode::kUnimplemented,
                       "[output] kinds lists \"dds\", but this skyloc was built without "
                       "Cyclone DDS (cyclonedds-dev and cyclonedds-tools were missing at build "
                       "time): remove \"dds\" or rebuild with them installed");
#endif
}

}  // namespace skyloc::firmware
