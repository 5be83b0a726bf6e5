#include "skyloc/sim/motion.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>
#include <utility>

#include "skyloc/sim/random.h"

namespace skyloc::sim {
namespace {

class ArcLength {
 public:
  ArcLength(std::span<const Point2> route, bool closed) {
    points_.assign(route.begin(), route.end());
    if (closed)
      points_.push_back(route.front());
    cumulative_.push_back(0);
    for (std::size_t i = 1; i < points_.size(); ++i) {
      cumulative_.push_back(cumulative_.back() + std::hypot(points_[i].x - points_[i - 1].x,
                                                            points_[i].y - points_[i - 1].y));
    }
    closed_ = closed;
  }
  double length() const { return cumulative_.back(); }
  Point2 At(double s) const {
    if (closed_)
      s = std::fmod(std::fmod(s, length()) + length(), length());
    s = std::clamp(s, 0.0, length());
    const auto it = std::lower_bound(cumulative_.begin(), cumulative_.end(), s);
    std::size_t i = std::clamp<std::size_t>(static_cast<std::size_t>(it - cumulative_.begin()), 1,
                                            points_.size() - 1);
    const double seg = cumulative_[i] - cumulative_[i - 1];
    const double f = seg > 0 ? (s - cumulative_[i - 1]) / seg : 0;
    return {points_[i - 1].x + f * (points_[i].x - points_[i - 1].x),
            points_[i - 1].y + f * (points_[i].y - points_[i - 1].y)};
  }

 private:
  std::vector<Point2> points_;
  std::vector<double> cumulative_;
  bool closed_ = false;
};

// Heading of the route at s from the chord over `window`, plus the manoeuvres' yaw.
double YawDeg(const ArcLength& path, bool closed, double end, double window, double s,
              const MotionConfig& config) {
  const Point2 behind = path.At(closed ? s - window / 2 : std::max(s - window / 2, 0.0));
  const Point2 ahead = path.At(closed ? s + window / 2 : std::min(s + window / 2, end));
  double yaw = std::atan2(ahead.y - behind.y, ahead.x - behind.x) * 180.0 / std::numbers::pi;
  yaw += config.yaw_offset_deg;
  if (config.zigzag_deg != 0 && config.zigzag_period_m > 0)
    yaw += config.zigzag_deg * std::sin(2 * std::numbers::pi * s / config.zigzag_period_m);
  return std::remainder(yaw, 360.0);
}

// Bumps: a bounded random walk, reflected at the bounds. `fraction` scales the step (time
// sampling: the share of a cruise frame's distance actually driven, so a standing robot
// does not bump).
void Bump(Rng& rng, double step_deg, double bound_deg, double fraction, double* roll,
          double* pitch) {
  *roll += fraction * rng.Uniform(-step_deg, step_deg);
  *pitch += fraction * rng.Uniform(-step_deg, step_deg);
  auto reflect = [&](double v) {
    if (v > bound_deg)
      return 2 * bound_deg - v;
    if (v < -bound_deg)
      return -2 * bound_deg - v;
    return v;
  };
  *roll = reflect(*roll);
  *pitch = reflect(*pitch);
}

Status CheckCommon(std::span<const Point2> route, const MotionConfig& config) {
  if (route.size() < 2)
    return Status::Error(StatusCode::kInvalidArgument, "a route needs at least two points");
  if (!(config.bumps_deg >= 0 && config.bumps_deg <= 45))
    return Status::Error(StatusCode::kInvalidArgument, "bumps must be within 0..45 degrees");
  if (!(config.fps > 0 && config.fps <= 1000))
    return Status::Error(StatusCode::kInvalidArgument, "fps must be within (0, 1000]");
  if (!(config.lateral_m >= 0 && config.lateral_m <= 5))
    return Status::Error(StatusCode::kInvalidArgument,
                         "lateral wander %g m: expected within 0..5 m (the worlds keep trees and "
                         "walls 2.5 m or more from the route)",
                         config.lateral_m);
  return Status::Ok();
}

Status BuildDistanceSampled(std::span<const Point2> route, bool closed, const MotionConfig& config,
                            std::vector<TrajectoryPoint>* out) {
  if (!(config.frame_spacing_m > 0))
    return Status::Error(StatusCode::kInvalidArgument, "frame spacing must be positive");
  if (!(config.speed_jitter >= 0 && config.speed_jitter < 1))
    return Status::Error(StatusCode::kInvalidArgument, "speed jitter must be in [0, 1)");
  const ArcLength path(route, closed);
  if (!(path.length() > 0))
    return Status::Error(StatusCode::kInvalidArgument, "the route has zero length");
  // Heading from the chord over a window: ant routes (1 cm steps) wiggle at small scales.
  const double window = std::clamp(2 * config.frame_spacing_m, 0.05, 2.0);
  Rng rng(config.seed * 0x2545F4914F6CDD1Dull + 7);
  out->clear();
  double s = config.start_m;
  const double end = closed ? config.start_m + path.length() : path.length();
  double speed = 1.0, roll = 0, pitch = 0;
  const double step_deg = config.bumps_deg * 0.2;
  const double period_s = 1.0 / config.fps;
  for (int i = 0; s <= end + 1e-9; ++i) {
    if (config.max_frames > 0 && i >= config.max_frames)
      break;
    const Point2 p = path.At(s);
    const double yaw = YawDeg(path, closed, end, window, s, config);
    if (config.bumps_deg > 0)
      Bump(rng, step_deg, config.bumps_deg, 1.0, &roll, &pitch);
    TrajectoryPoint t;
    t.pose = {p.x, p.y, config.height_m, roll, config.tilt_deg + pitch, yaw};
    t.time_s = i * period_s;
    t.route_m = closed ? std::fmod(s, path.length()) : s;
    if (config.speed_jitter > 0) {
      speed += rng.Uniform(-0.25, 0.25) * config.speed_jitter;
      speed = std::clamp(speed, 1 - config.speed_jitter, 1 + config.speed_jitter);
    }
    t.speed_mps = config.frame_spacing_m * speed * config.fps;
    out->push_back(t);
    s += config.frame_spacing_m * speed;
  }
  if (out->empty())
    return Status::Error(StatusCode::kInvalidArgument, "the start %g m is beyond the route's end",
                         config.start_m);
  return Status::Ok();
}

Status CheckProfile(const SpeedProfile& p, double speed_ratio) {
  if (!(p.cruise_mps > 0 && p.cruise_mps <= 100))
    return Status::Error(StatusCode::kInvalidArgument,
                         "cruise speed %g m/s: expected within (0, 100]", p.cruise_mps);
  if (!(p.band >= 0 && p.band < 1))
    return Status::Error(StatusCode::kInvalidArgument, "speed band %g: expected within [0, 1)",
                         p.band);
  if (!(p.change_every_m > 0))
    return Status::Error(StatusCode::kInvalidArgument,
                         "cruise changes every %g m: expected a positive distance",
                         p.change_every_m);
  if (!(p.accel_mps2 > 0 && p.accel_mps2 <= 100))
    return Status::Error(StatusCode::kInvalidArgument,
                         "acceleration limit %g m/s^2: expected within (0, 100]", p.accel_mps2);
  if (!(p.start_stop_s >= 0 && p.start_stop_s <= 3600))
    return Status::Error(StatusCode::kInvalidArgument,
                         "start stop %g s: expected within 0..3600 seconds", p.start_stop_s);
  if (p.stops < 0 || p.stops > 1000)
    return Status::Error(StatusCode::kInvalidArgument, "%d stops: expected 0..1000", p.stops);
  if (!(p.stop_min_s >= 0 && p.stop_min_s <= p.stop_max_s && p.stop_max_s <= 3600))
    return Status::Error(StatusCode::kInvalidArgument,
                         "stop duration %g..%g s: expected 0 <= min <= max <= 3600", p.stop_min_s,
                         p.stop_max_s);
  if (!(speed_ratio > 0 && speed_ratio <= 100))
    return Status::Error(StatusCode::kInvalidArgument, "speed ratio %g: expected within (0, 100]",
                         speed_ratio);
  return Status::Ok();
}

// The speed profile along the run, on a grid of route distance u (0 = the start). Between
// two nodes the acceleration is constant, so v^2 is linear in u and the motion within a
// cell is exact; a node may hold a dwell (a stop) during which the robot stands at it.
struct Profile {
  double du = 0;
  std::vector<double> v;       // speed at each node
  std::vector<double> dwell;   // seconds standing at each node
  std::vector<double> arrive;  // time the node is reached
};

// A stop never falls within one node of another stop or of the run's ends, so every cell
// has a positive speed at one end at least and is crossed in finite time.
void PlanProfile(double length, const MotionConfig& config, Profile* profile) {
  const SpeedProfile& p = config.speed;
  // 1 cm nodes (much finer than any frame step at 10 fps), at least 200 so stops keep clear
  // of the ends, at most 100000 so a long route costs a few megabytes.
  // The std::min makes n <= 100000 visible to the compiler: n + 1 cannot wrap, even with a
  // 32-bit size_t (armhf), which its null-dereference check needs to see.
  const std::size_t n = std::min<std::size_t>(
      static_cast<std::size_t>(std::clamp(std::ceil(length / 0.01), 200.0, 1e5)), 100000);
  const double du = length / static_cast<double>(n);
  profile->du = du;
  std::vector<double> cap(n + 1);
  // Cruise targets, changing at random places. A stream of its own: bumps do not move them.
  Rng rng(config.seed * 0x9E3779B97F4A7C15ull + 11);
  const double cruise = p.cruise_mps * config.speed_ratio;
  double next_change = 0, target = cruise;
  for (std::size_t j = 0; j <= n; ++j) {
    const double u = static_cast<double>(j) * du;
    while (u >= next_change) {
      target = cruise * (1 + p.band * rng.Uniform(-1, 1));
      next_change += p.change_every_m * rng.Uniform(0.5, 1.5);
    }
    cap[j] = target;
  }
  std::vector<double> dwell(n + 1, 0.0);
  cap[0] = cap[n] = 0;  // robots start standing and stop at the end of the route
  dwell[0] = p.start_stop_s;
  std::vector<std::size_t> stop_nodes;
  for (int k = 0; k < p.stops; ++k) {
    const double u = length * rng.Uniform(0.05, 0.95);
    const double seconds = rng.Uniform(p.stop_min_s, p.stop_max_s);
    auto j = static_cast<std::size_t>(std::lround(u / du));
    // Two stops drawn within a node of each other are one longer stop.
    for (const std::size_t other : stop_nodes) {
      if (j + 1 >= other && j <= other + 1)
        j = other;
    }
    if (cap[j] != 0)
      stop_nodes.push_back(j);
    cap[j] = 0;
    dwell[j] += seconds;
  }
  // Forward (acceleration) and backward (deceleration) passes: v_j^2 <= v_{j-1}^2 + 2 a du
  // both ways keeps |dv/dt| <= a within every cell.
  std::vector<double> v = cap;
  const double a2du = 2 * p.accel_mps2 * du;
  for (std::size_t j = 1; j <= n; ++j)
    v[j] = std::min(v[j], std::sqrt(v[j - 1] * v[j - 1] + a2du));
  for (std::size_t j = n; j-- > 0;)
    v[j] = std::min(v[j], std::sqrt(v[j + 1] * v[j + 1] + a2du));
  std::vector<double> arrive(n + 1, 0.0);
  for (std::size_t j = 0; j < n; ++j)
    arrive[j + 1] = arrive[j] + dwell[j] + 2 * du / (v[j] + v[j + 1]);
  profile->v = std::move(v);
  profile->dwell = std::move(dwell);
  profile->arrive = std::move(arrive);
}

Status BuildTimeSampled(std::span<const Point2> route, bool closed, const MotionConfig& config,
                        std::vector<TrajectoryPoint>* out) {
  SKYLOC_TRY(CheckProfile(config.speed, config.speed_ratio));
  const ArcLength path(route, closed);
  if (!(path.length() > 0))
    return Status::Error(StatusCode::kInvalidArgument, "the route has zero length");
  const double length = closed ? path.length() : path.length() - config.start_m;
  if (!(length > 0) || config.start_m < 0)
    return Status::Error(StatusCode::kInvalidArgument, "the start %g m is beyond the route's end",
                         config.start_m);
  Profile profile;
  PlanProfile(length, config, &profile);
  const std::size_t n = profile.v.size() - 1;
  const double period_s = 1.0 / config.fps;
  const double duration_s = profile.arrive[n];
  const double frames = std::ceil(duration_s * config.fps) + 1;
  constexpr double kMaxFrames = 1e7;  // a slow robot on a long route: refuse, do not swap
  if (config.max_frames == 0 && frames > kMaxFrames)
    return Status::Error(StatusCode::kInvalidArgument,
                         "the run would take %.0f frames (%.0f s at %g fps): raise the speed "
                         "or cap the frames",
                         frames, duration_s, config.fps);
  const double end = closed ? config.start_m + path.length() : path.length();
  const double nominal_step_m = config.speed.cruise_mps * config.speed_ratio / config.fps;
  const double window = std::clamp(2 * nominal_step_m, 0.05, 2.0);
  Rng rng(config.seed * 0x2545F4914F6CDD1Dull + 7);
  const double step_deg = config.bumps_deg * 0.2;
  double roll = 0, pitch = 0, previous_u = 0;
  out->clear();
  std::size_t j = 0;  // the node at or before the sample time
  for (int i = 0;; ++i) {
    if (config.max_frames > 0 && i >= config.max_frames)
      break;
    const double t = i * period_s;
    // The last frame is the first one at or after the arrival: standing at the route's end.
    if (i > 0 && (i - 1) * period_s >= duration_s)
      break;
    while (j < n && t >= profile.arrive[j + 1])
      ++j;
    if (t >= duration_s)
      j = n;  // past the arrival (also when rounding left the sum a hair above t)
    double u = static_cast<double>(j) * profile.du, v = 0;
    const double depart = profile.arrive[j] + profile.dwell[j];
    if (j == n) {
      u = length;  // arrived: exactly the end, not a rounding short of it
    } else if (t <= depart) {
      v = profile.dwell[j] > 0 ? 0 : profile.v[j];  // standing: u is bit-identical
    } else {
      // Constant acceleration within the cell: exact between the nodes.
      const double v0 = profile.v[j], v1 = profile.v[j + 1];
      const double accel = (v1 * v1 - v0 * v0) / (2 * profile.du);
      const double tau = t - depart;
      u = std::min(u + v0 * tau + 0.5 * accel * tau * tau, static_cast<double>(j + 1) * profile.du);
      v = std::max(v0 + accel * tau, 0.0);
    }
    const double s = config.start_m + u;
    if (config.bumps_deg > 0) {
      const double driven = std::min((u - previous_u) / nominal_step_m, 1.0);
      Bump(rng, step_deg, config.bumps_deg, driven, &roll, &pitch);
    }
    previous_u = u;
    const Point2 p = path.At(s);
    TrajectoryPoint point;
    point.pose = {p.x,
                  p.y,
                  config.height_m,
                  roll,
                  config.tilt_deg + pitch,
                  YawDeg(path, closed, end, window, s, config)};
    point.time_s = t;
    point.route_m = closed ? std::fmod(s, path.length()) : s;
    point.speed_mps = v;
    out->push_back(point);
  }
  return Status::Ok();
}

// Moves every pose sideways off the route by w(s) = A (0.6 sin(2 pi s / P1 + p1) + 0.4 sin(2 pi s /
// P2 + p2)), |w| <= A: a drift over tens of metres (P1 in 40..80 m) and a weave over a dozen
// (P2 in 12..25 m), as a driver holds a track only to a lane's width. `route_m` stays the
// distance along the route; eval's truth (the taught frames nearest by position) is the same
// stretch of route for an A of a metre or two. A stream of its own: the speed profile, stops
// and bumps do not move when A changes.
void WanderSideways(std::span<const Point2> route, bool closed, const MotionConfig& config,
                    std::vector<TrajectoryPoint>* out) {
  const ArcLength path(route, closed);
  Rng rng(config.seed * 0xD1B54A32D192ED03ull + 13);
  const double p1 = rng.Uniform(40, 80), p2 = rng.Uniform(12, 25);
  const double phase1 = rng.Uniform(0, 2 * std::numbers::pi);
  const double phase2 = rng.Uniform(0, 2 * std::numbers::pi);
  const double end = path.length();
  // The wander follows the distance driven, not `route_m`: on a closed loop route_m wraps to
  // 0 at the seam, where w(route_m) would jump sideways by up to 2 A in one frame.
  double laps = 0, previous_route_m = out->empty() ? 0 : out->front().route_m;
  for (TrajectoryPoint& t : *out) {
    if (closed && t.route_m < previous_route_m - end / 2)
      laps += end;
    previous_route_m = t.route_m;
    const double driven = t.route_m + laps;
    const double w =
        config.lateral_m * (0.6 * std::sin(2 * std::numbers::pi * driven / p1 + phase1) +
                            0.4 * std::sin(2 * std::numbers::pi * driven / p2 + phase2));
    const double s = t.route_m;
    // The route's own direction over 1 m (no manoeuvre yaw): left of it is +w.
    const Point2 behind = path.At(closed ? s - 0.5 : std::max(s - 0.5, 0.0));
    const Point2 ahead = path.At(closed ? s + 0.5 : std::min(s + 0.5, end));
    const double dx = ahead.x - behind.x, dy = ahead.y - behind.y;
    const double norm = std::hypot(dx, dy);
    if (!(norm > 0))
      continue;
    t.pose.x_m += -dy / norm * w;
    t.pose.y_m += dx / norm * w;
  }
}

}  // namespace

Status BuildTrajectory(std::span<const Point2> route, bool closed, const MotionConfig& config,
                       std::vector<TrajectoryPoint>* out) {
  SKYLOC_TRY(CheckCommon(route, config));
  SKYLOC_TRY(config.sampling == Sampling::kDistance
                 ? BuildDistanceSampled(route, closed, config, out)
                 : BuildTimeSampled(route, closed, config, out));
  if (config.lateral_m > 0)
    WanderSideways(route, closed, config, out);
  return Status::Ok();
}

Status LoadRouteCsv(const char* path, std::vector<Point2>* route) {
  std::FILE* f = std::fopen(path, "r");
  if (f == nullptr)
    return Status::FromErrno(errno, "cannot open route '%s'", path);
  char line[256];
  double scale = 0;
  int line_no = 0;
  Status status;
  route->clear();
  while (std::fgets(line, sizeof line, f) != nullptr) {
    ++line_no;
    if (line_no == 1) {
      if (std::strncmp(line, "x_cm,y_cm", 9) == 0) {
        scale = 0.01;
      } else if (std::strncmp(line, "x_m,y_m", 7) == 0) {
        scale = 1.0;
      } else {
        status = Status::Error(StatusCode::kInvalidArgument,
                               "%s:1: expected a header 'x_cm,y_cm,...' (centimetres, the "
                               "Seville ant routes) or 'x_m,y_m,...' (metres)",
                               path);
        break;
      }
      continue;
    }
    if (line[0] == '\n' || line[0] == '\r' || line[0] == '\0')
      continue;
    char* end = nullptr;
    const double x = std::strtod(line, &end);
    const bool x_ok = end != line && *end == ',';
    const char* rest = x_ok ? end + 1 : line;
    const double y = std::strtod(rest, &end);
    if (!x_ok || end == rest || !std::isfinite(x) || !std::isfinite(y)) {
      status = Status::Error(StatusCode::kInvalidArgument, "%s:%d: expected 'x,y' numbers", path,
                             line_no);
      break;
    }
    route->push_back({x * scale, y * scale});
  }
  std::fclose(f);
  SKYLOC_TRY(status);
  if (route->size() < 2)
    return Status::Error(StatusCode::kInvalidArgument, "%s: a route needs at least two points",
                         path);
  return Status::Ok();
}

}  // namespace skyloc::sim
