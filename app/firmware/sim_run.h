// From a simulated run's description (SimRunConfig, config.h) to what the simulator runs:
// the one conversion that the firmware's simulated camera and `skyloc simulate` share.
#pragma once

#include "firmware/config.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/motion.h"
#include "skyloc/sim/renderer.h"

namespace skyloc::firmware {

// `skyloc simulate`'s starting point: time sampling, and for the Seville world an ant's
// run (0.5 m/s cruise, the camera 1 cm above the ground).
SimRunConfig SimulateDefaults(bool seville);

// A firmware run on the simulated camera: the world and its sampling from the
// configuration's [camera] sim_* keys, the rest (the ride: run seed, attitude, speed ratio,
// camera height; the lighting) from the command line's SIM flags.
SimRunConfig ConfiguredSimRun(const SimWorldConfig& configured, const SimRunConfig& command_line);

// The motion of the run over `base`, which gives what a run does not describe (the zigzag
// period, lateral wander, start and frame limit: `skyloc simulate`'s own options); `fps`
// is the camera's frame rate (kTime samples at it, and it stamps the frames).
sim::MotionConfig SimMotionConfig(const SimRunConfig& run, double fps,
                                  const sim::MotionConfig& base = {});

// The lighting preset `run.lighting` with the run's seed; kInvalidArgument for a name
// that is not dawn, noon or overcast.
Result<sim::Lighting> SimLighting(const SimRunConfig& run);

}  // namespace skyloc::firmware
