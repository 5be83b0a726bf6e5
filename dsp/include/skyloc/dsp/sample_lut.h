// The per-sample pixel lookup table: for every sampling-grid direction (ring theta_i,
// longitude phi_j = 2 pi j / n_phi, in the body frame) where the lens maps it, built once
// at start-up. Sampling a frame is then a gather. With footprint 1 (the default) the value
// of sample (i, j) is the sky indicator (0 ground, 1 sky) read bilinearly at the direction's
// sub-pixel position: the 2 x 2 pixels around it, weighted by how close each is. With
// footprint k > 1 it is the mean indicator over the k x k pixels around the nearest pixel,
// equally weighted. Pixels the camera does not see (outside the image circle, beyond the
// field of view) count as ground, and so does a direction whose nearest pixel it does not
// see. Samples are written ring-major: index i * n_phi + j, the order the SH projector
// takes.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/image.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sh_grid.h"

namespace skyloc::dsp {

struct SampleLutOptions {
  // Footprint edge k (odd, 1..7): 1 reads the direction's sub-pixel position bilinearly
  // (4 reads); k > 1 averages the k x k pixels around the nearest pixel (k * k reads).
  // Bilinear, not the nearest pixel: a sample then changes smoothly as the sky's edge moves
  // across the pixels, where at the nearest pixel it flips whole (docs/SKY_DESCRIPTOR.md,
  // "Sampling").
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

  // Oriented sampling (the gravity-aligned cap, docs/SKY_DESCRIPTOR.md "Tilt"): the grid's
  // directions are in the *world* frame and Orient() points them through the body's
  // attitude every frame. A level table would need one entry per attitude, so Init builds
  // instead a table over the lens's whole field: body direction -> pixel, indexed by the
  // stereographic projection (x, y) / (1 + z), which needs no trigonometry per sample and
  // stays regular past 90 degrees from the zenith. Each direction is read bilinearly from
  // the 2 x 2 pixels around its sub-pixel position (footprint must be 1). The table takes
  // 8 bytes a cell (2 MiB).
  // Until the first Orient() the grid points along the body's axes (level).
  SampleLutError InitOriented(const Lens& lens, const ShGrid& grid,
                              const SampleLutOptions& options);
  // up: the world zenith in the body frame (unit). World direction w is looked up at body
  // direction Q w, Q the smallest rotation taking (0, 0, 1) to up (the yaw it leaves out does
  // not change an amplitude spectrum). No allocation. Only after InitOriented.
  void Orient(const std::array<double, 3>& up);
  // The skyline model of an upward view: along a world meridian the sky lies above the
  // skyline and the ground below it (no overhangs), so a direction the camera cannot see
  // (tilted away below its field of view) most likely has the value of the nearest seen
  // direction above it. Sets every unseen sample to the sample one ring up on its
  // longitude (0 on ring 0). Exact when the skyline is at or above the edge of the view.
  // Only after InitOriented and Orient: unseen directions leave the view going down a
  // meridian and never come back (the field of view is a cap about the body zenith).
  void FillUnseenFromAbove(std::span<float> samples) const;

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
  // Footprint 1: the 2 x 2 block whose top-left pixel is (x, y), mixed by fx, fy (1/256
  // pixel); bit k of `seen` says the camera sees pixel k of the block (0 top-left, 1
  // top-right, 2 bottom-left, 3 bottom-right). Footprint k > 1: one pixel (x, y), seen 1
  // or 0. A tap with seen == 0 reads as ground (for footprint 1: the direction is unseen,
  // which FillUnseenFromAbove tests).
  struct Tap {
    std::uint16_t x = 0;
    std::uint16_t y = 0;
    std::uint8_t fx = 0;
    std::uint8_t fy = 0;
    std::uint8_t seen = 0;
    std::uint8_t unused = 0;
  };
  // The bilinear tap of a sub-pixel position (unseen if the camera does not see its nearest
  // pixel).
  static Tap BilinearTap(const Lens& lens, double px, double py);

  template <typename Predicate>
  void Gather(const ImageView& image, const Predicate& is_sky, std::span<float> samples) const;

  int width_ = 0;
  int height_ = 0;
  int rings_ = 0;
  int n_phi_ = 0;
  int taps_per_sample_ = 1;  // 1: bilinear taps; k * k: box taps
  float tap_weight_ = 1.0f;
  double visible_fraction_ = 0.0;
  std::vector<Tap> taps_;  // size() * taps_per_sample_

  // Oriented sampling only.
  int table_cells_ = 0;    // the stereographic table is table_cells_ x table_cells_
  float table_rho_ = 0;    // its half-width: tan(theta_max / 2)
  float table_scale_ = 0;  // cells per unit of stereographic coordinate
  std::vector<Tap> table_;
  std::vector<float> ring_sin_, ring_cos_, cos_phi_, sin_phi_;
  std::vector<float> meridian_;  // per frame: 3 floats per longitude
};

}  // namespace skyloc::dsp
