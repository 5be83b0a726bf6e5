// Otsu's threshold (Otsu 1979): the grey level that maximises the between-class variance
// of a 256-bin histogram. The paper segments sky from ground with it (section III-A).
#pragma once

#include <array>
#include <cstdint>

namespace skyloc::dsp {

using Histogram256 = std::array<std::uint32_t, 256>;

// How far apart two classes of pixels must be to be sky and ground rather than one grey
// level and its noise (SeparatesSkyFromGround below). The image model: a frame is one
// level plus sensor noise (lens cap, saturated sensor, fog, a grey card), possibly shaded,
// or two such classes. Otsu splits a single class too, and then its class means lie at
// most 2*sqrt(3) = 3.46 pooled within-class standard deviations apart (a uniform spread,
// the flattest a single level's shading or noise can be; Gaussian noise gives 2.65).
inline constexpr double kMinClassSeparationSigmas = 4.0;
// A single level clipped at black or white (lens cap, saturated sensor) puts half its
// pixels in one bin and the rest in a tail, which reads as about 4 deviations apart; its
// class means are then 1.2 noise sigmas apart. 12 grey levels is that for a sensor noise
// of 10 levels, five times the simulator's and more than an 8-bit sensor shows at its
// highest gain, while sky and ground differ by tens of levels even under an overcast sky.
inline constexpr double kMinClassSeparationLevels = 12.0;

struct OtsuResult {
  // Pixels with value > threshold are the bright class (sky).
  int threshold = 0;
  // Between-class variance at the threshold, divided by the total variance (0..1):
  // near 1 for a clean bimodal image, near 0 when there is nothing to separate.
  double separability = 0.0;
  // The mean grey level of each class and their pooled within-class standard deviation,
  // counting each level as spread over its bin (quantisation, variance 1/12). 0 for an
  // empty class.
  double low_mean = 0.0;
  double high_mean = 0.0;
  double within_sigma = 0.0;
};

// An empty or single-valued histogram has nothing to separate: threshold 0, separability 0.
OtsuResult OtsuThreshold(const Histogram256& histogram);

// Whether the split separates two classes (sky and ground) rather than one level and its
// noise: both classes hold pixels and their means are kMinClassSeparationSigmas pooled
// within-class deviations and kMinClassSeparationLevels grey levels apart.
bool SeparatesSkyFromGround(const OtsuResult& split);

}  // namespace skyloc::dsp
