// The demo. Until the pipeline exists it describes generated fisheye sky images: a street
// canyon seen from below, drawn at several headings, so the output shows that the Otsu
// threshold, the sky fraction and the SH amplitude spectrum do not depend on the heading,
// while a different street (walls closer together) gives a clearly different descriptor.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>
#include <vector>

#include "commands.h"
#include "skyloc/dsp/image.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"

namespace skyloc::app {
namespace {

// Equidistant 185-degree fisheye filling the image circle. Two building walls at
// |x| = half_width m, 10 m high, camera 1.5 m up: a ray is blocked when it meets a wall
// below its top.
std::uint8_t StreetCanyonPixel(int x, int y, int size, double heading, double half_width) {
  const double c = (size - 1) / 2.0;
  const double dx = x - c, dy = y - c;
  const double r = std::hypot(dx, dy) / (size / 2.0);
  const double theta = r * (185.0 / 2.0) * std::numbers::pi / 180.0;  // from the zenith
  if (r > 1.0)
    return 8;  // outside the lens
  const double azimuth = std::atan2(dy, dx) + heading;
  const double across = std::fabs(std::sin(theta) * std::cos(azimuth));  // ray's x slope
  const double up = std::cos(theta);
  const bool building = across > 1e-9 && up > 0 ? (8.5 * across / half_width) > up : up <= 0;
  return building ? 40 : 220;
}

void Draw(std::vector<std::uint8_t>& pixels, int size, double heading, double half_width) {
  for (int y = 0; y < size; ++y)
    for (int x = 0; x < size; ++x)
      pixels[static_cast<std::size_t>(y) * static_cast<std::size_t>(size) +
             static_cast<std::size_t>(x)] = StreetCanyonPixel(x, y, size, heading, half_width);
}

}  // namespace

int RunDemo(std::span<char* const> args) {
  if (!args.empty()) {
    std::fprintf(stderr, "skyloc demo: takes no arguments\n");
    return kExitUsage;
  }
  constexpr int kSize = 480;
  constexpr int kBands = 32;
  dsp::LensParams params;
  params.width = kSize;
  params.height = kSize;
  params.fov_deg = 185.0;
  dsp::Lens lens;
  dsp::SkyDescriptor descriptor;
  dsp::SkyDescriptorOptions options;
  options.bands = kBands;
  options.grid = dsp::DefaultShGridConfig(2 * kBands);  // oversampled: the mask has hard edges
  if (lens.Init(params) != dsp::LensError::kOk || !descriptor.Init(lens, options).ok()) {
    std::fprintf(stderr, "skyloc demo: internal error building the descriptor\n");
    return kExitFailure;
  }
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(kSize) * kSize);
  const dsp::ImageView image{pixels.data(), kSize, kSize, kSize, dsp::PixelFormat::kGrey8};
  std::vector<float> reference(kBands), amplitudes(kBands);
  dsp::SegmentationResult seg;

  std::printf(
      "skyloc demo: street canyon (walls 4 m away) seen by a 185-degree fisheye, %dx%d,"
      " %d SH bands\n",
      kSize, kSize, kBands);
  std::printf("%12s %10s %14s %13s %s %14s\n", "heading_deg", "threshold", "separability",
              "sky_fraction", "    a_0     a_1     a_2     a_3", "L1_to_heading_0");
  for (int heading_deg = 0; heading_deg < 180; heading_deg += 30) {
    Draw(pixels, kSize, heading_deg * std::numbers::pi / 180.0, 4.0);
    if (!descriptor.Compute(image, amplitudes, &seg).ok())
      return kExitFailure;
    if (heading_deg == 0)
      reference = amplitudes;
    std::printf("%12d %10d %14.3f %13.4f  %6.3f  %6.3f  %6.3f  %6.3f %14.4f\n", heading_deg,
                seg.threshold, seg.separability, seg.sky_fraction,
                static_cast<double>(amplitudes[0]), static_cast<double>(amplitudes[1]),
                static_cast<double>(amplitudes[2]), static_cast<double>(amplitudes[3]),
                static_cast<double>(dsp::DescriptorDistance(reference, amplitudes)));
  }
  Draw(pixels, kSize, 0.0, 2.5);
  if (!descriptor.Compute(image, amplitudes, &seg).ok())
    return kExitFailure;
  std::printf("a different place (walls 2.5 m away): sky_fraction %.4f, L1 to the first: %.4f\n",
              seg.sky_fraction,
              static_cast<double>(dsp::DescriptorDistance(reference, amplitudes)));
  return kExitOk;
}

}  // namespace skyloc::app
