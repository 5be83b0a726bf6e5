// Trajectories: a route (polyline on the ground) sampled into camera poses at a frame
// spacing, with the manoeuvres of Stone et al. 2016: speed jitter (so SeqSLAM's velocity
// search matters), camera height, constant tilt about the pitch axis, zig-zag yaw, bumpy
// roll/pitch (a bounded random walk), and a constant yaw offset between runs.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/drivers/camera.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {

struct MotionConfig {
  double frame_spacing_m = 1.0;  // mean distance between frames
  double speed_jitter = 0.2;     // speed wanders within (1 +- jitter) x nominal
  double height_m = 1.0;         // camera above the ground
  double tilt_deg = 0;           // constant pitch (the paper's alpha), nose up positive
  double zigzag_deg = 0;         // yaw amplitude of a sinusoidal weave about the route
  double zigzag_period_m = 20;   // route distance of one full weave
  double bumps_deg = 0;          // roll/pitch random walk bound (0: smooth ride)
  double yaw_offset_deg = 0;     // constant heading offset (full yaw change between runs)
  double frame_period_s = 0.1;   // timestamp step
  double start_m = 0;            // where along the route the run starts
  int max_frames = 0;            // 0: until the end of the route (one lap of a loop)
  std::uint64_t seed = 1;        // speed jitter and bumps
};

struct TrajectoryPoint {
  drivers::Pose pose;
  double time_s = 0;
  double route_m = 0;  // arc length along the route: the ground truth for place matching
};

// Samples `route` (metres). Allocates `out` (start-up work).
Status BuildTrajectory(std::span<const Point2> route, bool closed, const MotionConfig& config,
                       std::vector<TrajectoryPoint>* out);

// A route CSV: header `x_cm,y_cm[,...]` (the Seville ant routes: centimetres) or
// `x_m,y_m[,...]` (metres); one point a row. Errors name the file and line.
Status LoadRouteCsv(const char* path, std::vector<Point2>* route);

}  // namespace skyloc::sim
