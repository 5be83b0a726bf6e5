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
//
// A frame is sampled in two passes. The first thresholds, row by row in memory order, only
// the pixels the table reads and the camera sees, into a plane of 0/1 bytes the table owns
// (every other byte of it stays 0: ground). The second is the gather: per sample one
// 8-byte entry (the block's offset in that plane and its two fractions) and four byte
// reads, mixed in integers. The pixel format, the stride and the camera's view then cost
// nothing per sample. The fractions are multiples of 1/256, so the mix is exact in 32-bit
// integers and its conversion to float is exact too: the same value, bit for bit, as the
// bilinear formula in floats.
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

  // From a binary mask (kGrey8; any non-zero byte is sky). Writes the table's own sky
  // plane, so not const; no allocation.
  SampleLutError SampleMask(const ImageView& mask, std::span<float> samples);
  // Straight from the frame: a pixel is sky when its channel mean is > threshold. Same
  // result as SampleMask on the mask Segment() would write, without writing it.
  SampleLutError SampleImage(const ImageView& image, int threshold, std::span<float> samples);

  int rings() const { return rings_; }
  int n_phi() const { return n_phi_; }
  std::size_t size() const {
    return static_cast<std::size_t>(rings_) * static_cast<std::size_t>(n_phi_);
  }
  // Fraction of samples whose centre direction the camera sees.
  double visible_fraction() const { return visible_fraction_; }

 private:
  // Footprint 1: the 2 x 2 block whose top-left pixel is at `offset` in the sky plane
  // (y * width + x), mixed by fx, fy (1/256 pixel). Footprint k > 1: the one pixel at
  // `offset`. `seen` is 0 for a direction the camera does not see (FillUnseenFromAbove
  // tests it); such a tap points at the plane's zero padding and reads as ground.
  struct Tap {
    std::uint32_t offset = 0;
    std::uint8_t fx = 0;
    std::uint8_t fy = 0;
    std::uint8_t seen = 0;
    std::uint8_t unused = 0;
  };
  // One run of pixels of row y, from column x, that the first pass thresholds: pixels the
  // camera sees, between the first and the last pixel of the row a tap reads.
  struct Run {
    std::uint16_t x = 0;
    std::uint16_t y = 0;
    std::uint32_t length = 0;
  };
  // The tap of a direction the camera does not see.
  Tap UnseenTap() const { return Tap{unseen_offset_, 0, 0, 0, 0}; }
  // The bilinear tap of a sub-pixel position (unseen if the camera does not see its nearest
  // pixel).
  Tap BilinearTap(const Lens& lens, double px, double py) const;
  // Sizes the sky plane (zero) and lists the runs the first pass thresholds: every pixel
  // the taps may read, seen by the camera.
  void PlanRuns(const Lens& lens, std::span<const Tap> taps);

  // The first pass: run_is_sky(pixels, plane bytes, count) for every run.
  template <typename RunIsSky>
  void Threshold(const ImageView& image, std::size_t pixel_bytes, const RunIsSky& run_is_sky);
  void Gather(std::span<float> samples) const;

  int width_ = 0;
  int height_ = 0;
  int rings_ = 0;
  int n_phi_ = 0;
  int taps_per_sample_ = 1;  // 1: bilinear taps; k * k: box taps
  float tap_weight_ = 1.0f;
  double visible_fraction_ = 0.0;
  std::uint32_t unseen_offset_ = 0;  // width * height: the start of the plane's padding
  std::vector<Tap> taps_;            // size() * taps_per_sample_
  std::vector<Run> runs_;
  // Per frame: 1 where a pixel is sky and seen, else 0; width * height bytes and a zero
  // padding of width + 2 bytes that unseen taps read.
  std::vector<std::uint8_t> sky_;

  // Oriented sampling only.
  int table_cells_ = 0;    // the stereographic table is table_cells_ x table_cells_
  float table_rho_ = 0;    // its half-width: tan(theta_max / 2)
  float table_scale_ = 0;  // cells per unit of stereographic coordinate
  std::vector<Tap> table_;
  std::vector<float> ring_sin_, ring_cos_, cos_phi_, sin_phi_;
  std::vector<float> meridian_;  // per frame: 3 floats per longitude
};

}  // namespace skyloc::dsp
