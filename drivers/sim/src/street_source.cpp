#include "skyloc/sim/street_source.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "skyloc/dsp/angles.h"
#include "skyloc/sim/random.h"

namespace skyloc::sim {
namespace {

constexpr double kStreetHalfWidth = 6.0;  // m, camera to the building fronts
constexpr double kCameraHeight = 0.3;     // m, a small robot
constexpr double kBlockLength = 7.0;      // m of street per building

// Height of the building at street position x on one side (0 = left, 1 = right).
double BuildingHeight(std::uint64_t seed, int side, double x) {
  const auto block = static_cast<std::int64_t>(std::floor(x / kBlockLength));
  const std::uint64_t key =
      seed * 1000003u + static_cast<std::uint64_t>(block) * 2u + static_cast<std::uint64_t>(side);
  const double u = SplitMix64Unit(key);
  if (u < 0.12)
    return 0.0;  // a gap: a side street or a yard
  return 3.0 + 22.0 * SplitMix64Unit(key ^ 0x5bd1e995u);
}

}  // namespace

StreetSource::StreetSource(const StreetOptions& options) : options_(options) {
  std::snprintf(name_, sizeof name_, "sim:street(seed %llu)",
                static_cast<unsigned long long>(options_.seed));
  Restart();
}

drivers::SimulatedCameraConfig StreetSource::camera_config() const {
  drivers::SimulatedCameraConfig c;
  c.width = options_.width;
  c.height = options_.height;
  c.format = dsp::PixelFormat::kGrey8;
  c.frame_interval = Nanoseconds(static_cast<std::int64_t>(1e9 / options_.fps));
  c.frame_count = options_.frames;
  c.paced = options_.paced;
  return c;
}

Status StreetSource::Prepare(int width, int height, dsp::PixelFormat format) {
  if (width < 16 || height < 16 || format != dsp::PixelFormat::kGrey8) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "street: %dx%d %s: needs at least 16x16 and grey frames", width, height,
                         dsp::PixelFormatName(format));
  }
  const int w = width, h = height;
  const std::size_t n = static_cast<std::size_t>(w) * static_cast<std::size_t>(h);
  SKYLOC_TRY(rays_.Allocate(3 * n));
  width_ = w;
  height_ = h;
  // The lens of LensFromConfig: equidistant, 185 degrees across the inscribed circle.
  const double cx = (w - 1) / 2.0, cy = (h - 1) / 2.0;
  const double radius = std::min(w, h) / 2.0;
  const double max_theta = 185.0 / 2.0 * dsp::kDegToRad;
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
  Restart();
  return Status::Ok();
}

std::optional<Nanoseconds> StreetSource::TimeOf(std::uint64_t index) const {
  return Nanoseconds(static_cast<std::int64_t>(static_cast<double>(index) * 1e9 / options_.fps));
}

void StreetSource::Restart() {
  at_ = 0;
  x_m_ = 0.0;
  rng_ = (options_.seed ^ 0xabcdef) + options_.run_seed * 0x9e3779b97f4a7c15ull;
}

void StreetSource::Step() {
  ++at_;
  rng_ = SplitMix64(rng_);
  const double jitter = options_.speed_jitter * (2.0 * SplitMix64Unit(rng_) - 1.0);
  x_m_ += options_.step_m * (1.0 + jitter);
}

Status StreetSource::Render(std::uint64_t index, dsp::MutableImageView out,
                            std::optional<drivers::Pose>* pose) {
  if (out.width != width_ || out.height != height_ || out.format != dsp::PixelFormat::kGrey8)
    return Status::Error(StatusCode::kFailedPrecondition, "street: Render() before Prepare()");
  if (index < at_)
    Restart();
  while (at_ < index)
    Step();  // frames the camera dropped: the robot drove on all the same

  const double phase = 2.0 * std::numbers::pi * static_cast<double>(index) / 40.0;
  const double yaw = (options_.yaw_deg + options_.zigzag_deg * std::sin(phase)) * dsp::kDegToRad;
  const double pitch = options_.tilt_deg * dsp::kDegToRad;
  const double cy = std::cos(yaw), sy = std::sin(yaw), cp = std::cos(pitch), sp = std::sin(pitch);
  const double sky = std::min(255.0, 210.0 * options_.brightness);
  const double wall = 45.0 * options_.brightness;
  const double ground = 25.0 * options_.brightness;
  for (int y = 0; y < height_; ++y) {
    std::uint8_t* row = out.Row(y);
    for (int x = 0; x < width_; ++x) {
      const std::size_t p = static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) +
                            static_cast<std::size_t>(x);
      const double r[3] = {rays_[3 * p], rays_[3 * p + 1], rays_[3 * p + 2]};
      if (std::isnan(r[0])) {
        row[x] = 0;
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
          const double hit_x = x_m_ + bx * t;
          if (hit_height < BuildingHeight(options_.seed, by > 0 ? 1 : 0, hit_x))
            v = wall;
        }
      }
      // Deterministic sensor noise, +-6 grey levels, different on every run. The pixel
      // index is widened first: size_t is 32 bits on armhf, where p * 0x9e37 wrapped past
      // pixel 106,039 (a 640x480 frame's lower two thirds had other noise than x86-64's).
      v += 12.0 * (SplitMix64Unit(static_cast<std::uint64_t>(p) * 0x9e37u + index +
                                  options_.run_seed * 0xd1b54a32d192ed03ull) -
                   0.5);
      row[x] = static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
    }
  }
  if (pose != nullptr) {
    drivers::Pose p;
    p.x_m = x_m_;
    p.z_m = kCameraHeight;
    p.pitch_deg = options_.tilt_deg;
    p.yaw_deg = yaw / dsp::kDegToRad;
    *pose = p;
  }
  return Status::Ok();
}

}  // namespace skyloc::sim
