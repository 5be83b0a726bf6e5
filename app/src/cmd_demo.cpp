// The demo. Until the pipeline exists it segments generated fisheye sky images: a street
// canyon seen from below, drawn at several headings, so the output shows that the sky
// fraction and Otsu threshold do not depend on the heading.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <vector>

#include "commands.h"
#include "skyloc/dsp/image.h"
#include "skyloc/dsp/otsu.h"

namespace skyloc::app {
namespace {

// Equidistant 185-degree fisheye: elevation of the ray through pixel (x, y), or NaN
// outside the image circle. Two building walls at |x| = 4 m, 10 m high, camera 1.5 m up.
std::uint8_t StreetCanyonPixel(int x, int y, int size, double heading) {
  const double c = (size - 1) / 2.0;
  const double dx = x - c, dy = y - c;
  const double r = std::hypot(dx, dy) / c;
  const double theta = r * (185.0 / 2.0) * std::numbers::pi / 180.0;  // from the zenith
  if (r > 1.0)
    return 8;  // outside the lens
  const double azimuth = std::atan2(dy, dx) + heading;
  const double across = std::fabs(std::sin(theta) * std::cos(azimuth));  // ray's x slope
  const double up = std::cos(theta);
  const bool building = across > 1e-9 && up > 0 ? (8.5 * across / 4.0) > up : up <= 0;
  return building ? 40 : 220;
}

}  // namespace

int RunDemo(std::span<char* const> args) {
  if (!args.empty()) {
    std::fprintf(stderr, "skyloc demo: takes no arguments\n");
    return kExitUsage;
  }
  constexpr int kSize = 480;
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(kSize) * kSize);
  std::printf("skyloc demo: street canyon seen by a 185-degree fisheye, %dx%d\n", kSize, kSize);
  std::printf("%12s %10s %14s %13s\n", "heading_deg", "threshold", "separability", "sky_fraction");
  for (int heading_deg = 0; heading_deg < 180; heading_deg += 30) {
    const double heading = heading_deg * std::numbers::pi / 180.0;
    dsp::Histogram256 histogram{};
    for (int y = 0; y < kSize; ++y) {
      for (int x = 0; x < kSize; ++x) {
        const std::uint8_t v = StreetCanyonPixel(x, y, kSize, heading);
        pixels[static_cast<std::size_t>(y) * kSize + static_cast<std::size_t>(x)] = v;
        ++histogram[v];
      }
    }
    const dsp::OtsuResult otsu = dsp::OtsuThreshold(histogram);
    std::size_t sky = 0;
    for (std::uint8_t v : pixels)
      sky += v > otsu.threshold ? 1 : 0;
    std::printf("%12d %10d %14.3f %13.4f\n", heading_deg, otsu.threshold, otsu.separability,
                static_cast<double>(sky) / static_cast<double>(pixels.size()));
  }
  return kExitOk;
}

}  // namespace skyloc::app
