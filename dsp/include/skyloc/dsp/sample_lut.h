// The per-sample pixel lookup table: for every sampling-grid direction (ring theta_i,
// longitude phi_j = 2 pi j / n_phi, in the body frame) the pixel(s) the lens maps it to,
// built once at start-up. Sampling a frame is then a gather: the value of sample
// (i, j) is the mean sky indicator (0 ground, 1 sky) over its footprint of k x k pixels
// around the projected pixel, equally weighted; pixels that are not visible (outside the
// image circle, beyond the field of view) count as ground. Samples are written
// ring-major: index i * n_phi + j, the order the SH projector takes.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/image.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sh_grid.h"

namespace skyloc::dsp {

struct SampleLutOptions {
  // Footprint edge k (odd, 1..7): 1 samples the nearest pixel; 3 averages 3 x 3 pixels,
  // which smooths the staircase of the mask edge at the cost of 9 reads per sample.
  int footprint = 1;
};

enum class SampleLutError : std::uint8_t {
  kOk,
  kBadFootprint,   // not odd or outside 1..7
  kBadGrid,        // no rings, n_phi < 1, or a ring angle outside [0, pi]
  kSizeMismatch,   // the frame or mask is not the lens's image size
  kBadOutputSize,  // samples span is not rings * n_phi
};

const char* SampleLutErrorMessage(SampleLutError error);

class SampleLut {
 public:
  // Projects every grid direction through the lens. Not for the frame path.
  SampleLutError Init(const Lens& lens, std::span<const double> ring_theta, int n_phi,
                      const SampleLutOptions& options);
  // The same for the rings and longitudes of an SH grid.
  SampleLutError Init(const Lens& lens, const ShGrid& grid, const SampleLutOptions& options);

  // From a binary mask (kGrey8; any non-zero byte is sky).
  SampleLutError SampleMask(const ImageView& mask, std::span<float> samples) const;
  // Straight from the frame: a pixel is sky when its channel mean is > threshold. Same
  // result as SampleMask on the mask Segment() would write, without writing it.
  SampleLutError SampleImage(const ImageView& image, int threshold, std::span<float> samples) const;

  int rings() const { return rings_; }
  int n_phi() const { return n_phi_; }
  std::size_t size() const {
    return static_cast<std::size_t>(rings_) * static_cast<std::size_t>(n_phi_);
  }
  // Fraction of samples whose centre direction the camera sees.
  double visible_fraction() const { return visible_fraction_; }

 private:
  struct Tap {
    std::uint16_t x;
    std::uint16_t y;  // kInvisible: the tap is ground
  };
  static constexpr std::uint16_t kInvisible = 0xffff;

  template <typename Predicate>
  void Gather(const ImageView& image, const Predicate& is_sky, std::span<float> samples) const;

  int width_ = 0;
  int height_ = 0;
  int rings_ = 0;
  int n_phi_ = 0;
  int taps_per_sample_ = 1;
  float tap_weight_ = 1.0f;
  double visible_fraction_ = 0.0;
  std::vector<Tap> taps_;  // size() * taps_per_sample_
};

}  // namespace skyloc::dsp
