// The drivers a session opens, made from the configuration: the camera (a real one, a
// dataset or the simulator's), the attitude source, the status lines and the DDS output.
// Each Make* names the configuration's key when the driver cannot open or this build has
// no such driver. Used by the session only (session.cpp).
#pragma once

#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "firmware/config.h"
#include "firmware/session.h"
#include "skyloc/drivers/attitude_source.h"
#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/frame_source.h"
#include "skyloc/drivers/imu_device.h"
#include "skyloc/drivers/localisation_output.h"
#include "skyloc/drivers/status_output.h"
#include "skyloc/platform/clock.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/world.h"

namespace skyloc::firmware {

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

// The camera the configuration names, or the dataset `args.dataset` names; a simulated
// one with its world and trajectory (`args.sim` gives the run). Opened.
Status MakeCamera(const Config& config, const SessionArgs& args, CameraSource* source);

// [attitude]: the source, opened; `camera` gives a dataset's attitude or a simulated
// run's trajectory.
Status MakeAttitudeSource(const Config& config, const CameraSource& camera, AttitudeParts* out);

// [status]: none (null), the simulated lines or the GPIO lines, not yet opened.
Result<std::unique_ptr<drivers::StatusOutput>> MakeStatusOutput(const Config& config,
                                                                const Clock* clock);

// [output] kinds = "dds": the ROS 2 topics through Cyclone DDS, when this build has it.
Result<std::unique_ptr<drivers::LocalisationOutput>> MakeDdsOutput(const OutputConfig& o);

}  // namespace skyloc::firmware
