#include "street_camera.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <thread>

namespace skyloc::app {
namespace {

constexpr double kStreetHalfWidth = 6.0;  // m, camera to the building fronts
constexpr double kCameraHeight = 0.3;     // m, a small robot
constexpr double kBlockLength = 7.0;      // m of street per building

std::uint64_t Mix(std::uint64_t x) {  // splitmix64
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

double Unit(std::uint64_t x) {
  return static_cast<double>(Mix(x) >> 11) * (1.0 / 9007199254740992.0);
}

// Height of the building at street position x on one side (0 = left, 1 = right).
double BuildingHeight(std::uint64_t seed, int side, double x) {
  const auto block = static_cast<std::int64_t>(std::floor(x / kBlockLength));
  const std::uint64_t key =
      seed * 1000003u + static_cast<std::uint64_t>(block) * 2u + static_cast<std::uint64_t>(side);
  const double u = Unit(key);
  if (u < 0.12)
    return 0.0;  // a gap: a side street or a yard
  return 3.0 + 22.0 * Unit(key ^ 0x5bd1e995u);
}

}  // namespace

Status StreetCamera::DoOpen() {
  const int w = options_.width, h = options_.height;
  if (w < 16 || h < 16)
    return Status::Error(StatusCode::kInvalidArgument, "street camera: %dx%d is too small", w, h);
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  SKYLOC_TRY(rays_.Allocate(3 * n));
  SKYLOC_TRY(pixels_.Allocate(n));
  // The lens of LensFromConfig: equidistant, 185 degrees across the inscribed circle.
  const double cx = (w - 1) / 2.0, cy = (h - 1) / 2.0;
  const double radius = std::min(w, h) / 2.0;
  const double max_theta = 185.0 / 2.0 * std::numbers::pi / 180.0;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      const std::size_t i = 3 * (static_cast<std::size_t>(y) * static_cast<std::size_t>(w) +
                                 static_cast<std::size_t>(x));
      const double dx = x - cx, dy = y - cy;
      const double r = std::hypot(dx, dy);
      if (r > radius) {
        rays_[i] = std::nanf("");
        continue;
      }
      const double theta = r / radius * max_theta;
      const double phi = std::atan2(dy, dx);
      rays_[i] = static_cast<float>(std::sin(theta) * std::cos(phi));
      rays_[i + 1] = static_cast<float>(std::sin(theta) * std::sin(phi));
      rays_[i + 2] = static_cast<float>(std::cos(theta));
    }
  }
  std::snprintf(info_.name, sizeof info_.name, "sim:street(seed %llu)",
                static_cast<unsigned long long>(options_.seed));
  info_.width = w;
  info_.height = h;
  info_.format = dsp::PixelFormat::kGrey8;
  return Status::Ok();
}

Status StreetCamera::DoStart() {
  start_ = clock_.Now();
  next_ = 0;
  x_m_ = 0.0;
  rng_ = (options_.seed ^ 0xabcdef) + options_.run_seed * 0x9e3779b97f4a7c15ull;
  return Status::Ok();
}

void StreetCamera::Render(double x_m, double yaw, double pitch) {
  const int w = options_.width, h = options_.height;
  const double cy = std::cos(yaw), sy = std::sin(yaw), cp = std::cos(pitch), sp = std::sin(pitch);
  const double sky = std::min(255.0, 210.0 * options_.brightness);
  const double wall = 45.0 * options_.brightness;
  const double ground = 25.0 * options_.brightness;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  for (std::size_t p = 0; p < n; ++p) {
    const double r[3] = {rays_[3 * p], rays_[3 * p + 1], rays_[3 * p + 2]};
    if (std::isnan(r[0])) {
      pixels_[p] = 0;
      continue;
    }
    // Camera -> body: pitch about y, then yaw about z.
    const double x1 = cp * r[0] + sp * r[2];
    const double z1 = -sp * r[0] + cp * r[2];
    const double bx = cy * x1 - sy * r[1];
    const double by = sy * x1 + cy * r[1];
    const double bz = z1;
    double v = ground;
    if (bz > 0) {
      v = sky * (0.85 + 0.15 * bz);  // brighter towards the zenith
      if (std::fabs(by) > 1e-6) {
        const double t = kStreetHalfWidth / std::fabs(by);
        const double hit_height = kCameraHeight + bz * t;
        const double hit_x = x_m + bx * t;
        if (hit_height < BuildingHeight(options_.seed, by > 0 ? 1 : 0, hit_x))
          v = wall;
      }
    }
    // Deterministic sensor noise, +-6 grey levels, different on every run.
    v += 12.0 * (Unit(p * 0x9e37u + next_ + options_.run_seed * 0xd1b54a32d192ed03ull) - 0.5);
    pixels_[p] = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
  }
}

Result<drivers::Frame> StreetCamera::DoCapture(Nanoseconds) {
  if (options_.frames != 0 && next_ >= options_.frames)
    return Status::Error(StatusCode::kOutOfRange, "street camera: end of the run");
  constexpr double kDeg = std::numbers::pi / 180.0;
  const double phase = 2.0 * std::numbers::pi * static_cast<double>(next_) / 40.0;
  const double yaw = (options_.yaw_deg + options_.zigzag_deg * std::sin(phase)) * kDeg;
  const double pitch = options_.tilt_deg * kDeg;
  Render(x_m_, yaw, pitch);
  const Nanoseconds due =
      start_ +
      Nanoseconds(static_cast<std::int64_t>(static_cast<double>(next_) * 1e9 / options_.fps));
  if (options_.paced && clock_.Now() < due)
    std::this_thread::sleep_for(due - clock_.Now());

  drivers::Frame frame;
  frame.image = {pixels_.data(), options_.width, options_.height,
                 static_cast<std::size_t>(options_.width), dsp::PixelFormat::kGrey8};
  frame.sequence = next_;
  frame.timestamp =
      Nanoseconds(static_cast<std::int64_t>(static_cast<double>(next_) * 1e9 / options_.fps));
  drivers::Pose pose;
  pose.x_m = x_m_;
  pose.z_m = kCameraHeight;
  pose.pitch_deg = options_.tilt_deg;
  pose.yaw_deg = yaw / kDeg;
  frame.pose = pose;
  ++counters_.frames;

  ++next_;
  rng_ = Mix(rng_);
  const double jitter = options_.speed_jitter * (2.0 * Unit(rng_) - 1.0);
  x_m_ += options_.step_m * (1.0 + jitter);
  return frame;
}

}  // namespace skyloc::app
