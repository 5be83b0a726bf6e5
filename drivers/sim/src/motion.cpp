#include "skyloc/sim/motion.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>

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

}  // namespace

Status BuildTrajectory(std::span<const Point2> route, bool closed, const MotionConfig& config,
                       std::vector<TrajectoryPoint>* out) {
  if (route.size() < 2)
    return Status::Error(StatusCode::kInvalidArgument, "a route needs at least two points");
  if (!(config.frame_spacing_m > 0))
    return Status::Error(StatusCode::kInvalidArgument, "frame spacing must be positive");
  if (!(config.speed_jitter >= 0 && config.speed_jitter < 1))
    return Status::Error(StatusCode::kInvalidArgument, "speed jitter must be in [0, 1)");
  if (!(config.bumps_deg >= 0 && config.bumps_deg <= 45))
    return Status::Error(StatusCode::kInvalidArgument, "bumps must be within 0..45 degrees");
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
  for (int i = 0; s <= end + 1e-9; ++i) {
    if (config.max_frames > 0 && i >= config.max_frames)
      break;
    const Point2 p = path.At(s);
    const Point2 behind = path.At(closed ? s - window / 2 : std::max(s - window / 2, 0.0));
    const Point2 ahead = path.At(closed ? s + window / 2 : std::min(s + window / 2, end));
    double yaw = std::atan2(ahead.y - behind.y, ahead.x - behind.x) * 180.0 / std::numbers::pi;
    yaw += config.yaw_offset_deg;
    if (config.zigzag_deg != 0 && config.zigzag_period_m > 0)
      yaw += config.zigzag_deg * std::sin(2 * std::numbers::pi * s / config.zigzag_period_m);
    yaw = std::remainder(yaw, 360.0);
    if (config.bumps_deg > 0) {
      // Bounded random walk, reflected at the bounds.
      roll += rng.Uniform(-step_deg, step_deg);
      pitch += rng.Uniform(-step_deg, step_deg);
      auto reflect = [&](double v) {
        if (v > config.bumps_deg)
          return 2 * config.bumps_deg - v;
        if (v < -config.bumps_deg)
          return -2 * config.bumps_deg - v;
        return v;
      };
      roll = reflect(roll);
      pitch = reflect(pitch);
    }
    TrajectoryPoint t;
    t.pose = {p.x, p.y, config.height_m, roll, config.tilt_deg + pitch, yaw};
    t.time_s = i * config.frame_period_s;
    t.route_m = closed ? std::fmod(s, path.length()) : s;
    out->push_back(t);
    if (config.speed_jitter > 0) {
      speed += rng.Uniform(-0.25, 0.25) * config.speed_jitter;
      speed = std::clamp(speed, 1 - config.speed_jitter, 1 + config.speed_jitter);
    }
    s += config.frame_spacing_m * speed;
  }
  if (out->empty())
    return Status::Error(StatusCode::kInvalidArgument, "the start %g m is beyond the route's end",
                         config.start_m);
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
