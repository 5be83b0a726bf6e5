// Trajectories: a route (polyline on the ground) sampled into camera poses, with the
// manoeuvres of Stone et al. 2016: camera height, constant tilt about the pitch axis,
// zig-zag yaw, bumpy roll/pitch (a bounded random walk), a constant yaw offset between
// runs, and a sideways wander off the route's line (a repeat drive never retraces the taught
// line exactly). Two samplings:
//  - distance: a frame every `frame_spacing_m` with speed jitter (so SeqSLAM's velocity
//    search matters); the original behaviour, kept bit for bit;
//  - time: a frame every 1/fps seconds while the robot follows a speed profile (starts
//    standing, accelerates, cruises at changing speeds, stops for seconds), as a real
//    camera at a fixed frame rate sees it. docs/SIMULATOR.md, "Motion".
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/drivers/camera.h"
#include "skyloc/platform/status.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {

enum class Sampling : std::uint8_t {
  kDistance,  // a frame every frame_spacing_m of route (with speed jitter)
  kTime,      // a frame every 1/fps seconds along the speed profile
};

// Sampling::kTime: how the robot drives. Every speed is reached with at most accel_mps2;
// a stop is a place where the speed is exactly 0 for its duration, so its frames repeat.
struct SpeedProfile {
  double cruise_mps = 1.0;     // mean cruise speed (times Ride::speed_ratio)
  double band = 0.3;           // cruise targets are drawn within cruise x (1 +- band)
  double change_every_m = 30;  // mean route distance between new cruise targets
  double accel_mps2 = 0.5;     // acceleration and deceleration limit
  double start_stop_s = 2.0;   // standing still before the run starts moving
  int stops = 2;               // further stops, at random places along the route
  double stop_min_s = 2.0;     // each stop lasts a random time within min..max
  double stop_max_s = 6.0;

  bool operator==(const SpeedProfile&) const = default;
};

// How a run is cut into frames. The configuration's [camera] sim_* keys and the
// experiments' options hold one; a MotionConfig is one with the ride on top.
struct FrameSampling {
  Sampling sampling = Sampling::kDistance;
  double frame_spacing_m = 1.0;  // kDistance: mean distance between frames
  double speed_jitter = 0.2;     // kDistance: speed wanders within (1 +- jitter) x nominal
  SpeedProfile speed;            // kTime

  bool operator==(const FrameSampling&) const = default;
};

// How the robot rides a run: its pace, the camera's height and manoeuvres, and the run's
// seed. A simulated run's description (the firmware's SimRunConfig) holds one; a
// MotionConfig is one.
struct Ride {
  double speed_ratio = 1.0;   // kTime: scales every cruise speed (a faster repeat run)
  double height_m = 1.0;      // camera above the ground
  double tilt_deg = 0;        // constant pitch (the paper's alpha), nose up positive
  double zigzag_deg = 0;      // yaw amplitude of a sinusoidal weave about the route
  double bumps_deg = 0;       // roll/pitch random walk bound (0: smooth ride)
  double yaw_offset_deg = 0;  // constant heading offset (full yaw change between runs)
  std::uint64_t seed = 1;     // speed jitter or profile (targets, stops), and bumps

  bool operator==(const Ride&) const = default;
};

// A run: how it is sampled into frames, how the robot rides it, the weave's period, the
// sideways wander, the frame rate, and where it starts and how long it goes.
struct MotionConfig : FrameSampling, Ride {
  // The same ride sampled as `frames` says.
  void Resample(const FrameSampling& frames) { static_cast<FrameSampling&>(*this) = frames; }
  // The same sampling with `ride` as its ride.
  void SetRide(const Ride& ride) { static_cast<Ride&>(*this) = ride; }

  double zigzag_period_m = 20;  // route distance of one full weave
  double lateral_m = 0;         // sideways wander off the route within +-lateral_m (0: on it)
  double fps = 10;              // frames per second: kTime samples at it; timestamps i / fps
  double start_m = 0;           // where along the route the run starts
  int max_frames = 0;           // 0: until the end of the route (one lap of a loop)
};

struct TrajectoryPoint {
  drivers::Pose pose;
  double time_s = 0;
  double route_m = 0;    // arc length along the route: the ground truth for place matching
  double speed_mps = 0;  // kTime: the speed at time_s; kDistance: the speed to the next frame
};

// Samples `route` (metres). Allocates `out` (start-up work).
Status BuildTrajectory(std::span<const Point2> route, bool closed, const MotionConfig& config,
                       std::vector<TrajectoryPoint>* out);

// A route CSV: header `x_cm,y_cm[,...]` (the Seville ant routes: centimetres) or
// `x_m,y_m[,...]` (metres); one point a row. Errors name the file and line.
Status LoadRouteCsv(const char* path, std::vector<Point2>* route);

}  // namespace skyloc::sim
