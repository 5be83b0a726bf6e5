#include <cmath>
#include <cstddef>
#include <numbers>

#include "skyloc/drivers/frame_source.h"

namespace skyloc::drivers {
namespace {

// Elevation (radians above the horizon) of the skyline at azimuth `az`: a few smooth
// hills plus blocky buildings, so the sky shape is neither trivial nor symmetric.
double SkylineElevation(double az) {
  const double hills = 0.15 + 0.08 * std::sin(3.0 * az) + 0.05 * std::sin(7.0 * az + 1.0);
  const int sector = static_cast<int>(std::floor(az / (std::numbers::pi / 8.0)));
  const double building = (sector % 3 == 0) ? 0.35 : ((sector % 5 == 1) ? 0.25 : 0.0);
  return hills > building ? hills : building;
}

}  // namespace

double SyntheticSkySource::YawDeg(std::uint64_t index) const {
  return std::fmod(static_cast<double>(index) * config_.yaw_step_deg, 360.0);
}

std::uint8_t SyntheticSkySource::GreyAt(std::uint64_t index, int x, int y, int width,
                                        int height) const {
  const double cx = 0.5 * width;
  const double cy = 0.5 * height;
  const double radius = 0.5 * (width < height ? width : height);
  const double dx = (x + 0.5) - cx;
  const double dy = (y + 0.5) - cy;
  const double r = std::sqrt(dx * dx + dy * dy);
  if (r >= radius)
    return 0;
  // Equidistant fisheye: the distance from the centre is proportional to the zenith angle.
  const double elevation = 0.5 * std::numbers::pi * (1.0 - r / radius);
  const double yaw = YawDeg(index) * std::numbers::pi / 180.0;
  double az = std::atan2(dy, dx) + yaw;
  az = std::fmod(az, 2.0 * std::numbers::pi);
  if (az < 0)
    az += 2.0 * std::numbers::pi;
  return elevation > SkylineElevation(az) ? config_.sky_level : config_.obstacle_level;
}

Status SyntheticSkySource::Render(std::uint64_t index, dsp::MutableImageView out,
                                  std::optional<Pose>* pose) {
  for (int y = 0; y < out.height; ++y) {
    std::uint8_t* row = out.Row(y);
    for (int x = 0; x < out.width; ++x) {
      const std::uint8_t v = GreyAt(index, x, y, out.width, out.height);
      const auto ux = static_cast<std::size_t>(x);
      switch (out.format) {
        case dsp::PixelFormat::kGrey8:
          row[ux] = v;
          break;
        case dsp::PixelFormat::kYuyv:
          row[2 * ux] = v;        // Y
          row[2 * ux + 1] = 128;  // U or V: no colour
          break;
        case dsp::PixelFormat::kRgb24:
        case dsp::PixelFormat::kBgr24:
          row[3 * ux] = v;
          row[3 * ux + 1] = v;
          row[3 * ux + 2] = v;
          break;
      }
    }
  }
  if (pose != nullptr) {
    Pose p;
    p.x_m = static_cast<double>(index) * config_.step_m;
    p.yaw_deg = YawDeg(index);
    *pose = p;
  }
  return Status::Ok();
}

}  // namespace skyloc::drivers
