// The horizon strip: a 1-D, 360-degree signal read from a band of elevations just above
// the horizon, the input of 1D SURF (Anderson et al. 2012 sum a 30-pixel band around the
// horizon at every 4th column of a forward camera; we sample the same kind of band
// through the lens model of an upward fisheye or an equirectangular panorama).
//
// Column j looks at body-frame azimuth phi_j = 2 pi j / n_azimuth, measured from +x
// towards +y (the lens.h convention). Its value is the mean, over the band's rows, of the
// per-pixel channel mean (GREY as is, RGB24/BGR24 (R + G + B) / 3 in integers, YUYV the Y
// byte: what SkySegmenter reads). The band's rows are band_rows elevations spread evenly
// over [elevation_min_deg, elevation_max_deg] (elevation above the horizon, i.e. 90
// degrees minus the angle from body +z). Each tap is the nearest pixel. Taps the camera
// cannot see (beyond the field of view, outside the image) are left out of the mean; a
// column with no visible tap reads 0.
//
// A change of robot heading is a circular shift of the strip: a scene that turns by +psi
// about body z (content at azimuth phi moves to phi + psi) shifts the strip by
// +psi * n_azimuth / 360 columns.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/image.h"
#include "skyloc/dsp/lens.h"

namespace skyloc::dsp {

struct HorizonStripOptions {
  int n_azimuth = 360;  // strip length: columns over 360 degrees
  int band_rows = 16;   // elevations sampled per column
  double elevation_min_deg = 0.0;
  double elevation_max_deg = 20.0;

  bool operator==(const HorizonStripOptions&) const = default;
};

enum class HorizonStripError : std::uint8_t {
  kOk,
  kBadOptions,     // n_azimuth outside 8..65536, band_rows outside 1..256, or band outside
                   // [-90, 90] / min > max
  kNotVisible,     // the lens sees none of the band: check elevation band and fov
  kSizeMismatch,   // the frame is not the lens's image size
  kBadOutputSize,  // the strip span is not n_azimuth long
};

// A sentence naming the problem and the fix.
const char* HorizonStripErrorMessage(HorizonStripError error);

// A strip as a route stores it: each column's grey level rounded to the nearest byte,
// clamped to 0..255. kBadOutputSize when `bytes` is not as long as `strip`. Allocates nothing.
HorizonStripError StripToBytes(std::span<const float> strip, std::span<std::uint8_t> bytes);

// A strip in 4 bits a column (route format 6, docs/SURF1D.md "What the route stores"):
// byte 0 is the strip's lowest byte lo, byte 1 its range r = highest - lo, then column
// 2i in the low nibble and 2i + 1 in the high nibble of byte 2 + i (an odd last column's
// high nibble is 0). The bytes lo..lo + r, each standing for [v - 0.5, v + 0.5), are cut
// into 16 equal levels, k = floor((v - lo + 0.5) * 16 / (r + 1)), and a level decodes as
// its centre, lo - 0.5 + (k + 0.5) (r + 1) / 16: within (r + 1) / 32 grey levels of the
// byte (8 at the widest range), exact when r = 15, and exact in float on every machine
// (an integer over 32). Per strip, not per route: teach writes each frame as it comes.
inline constexpr std::size_t PackedStripBytes(std::size_t columns) {
  return 2 + (columns + 1) / 2;
}
// kBadOutputSize when `packed` is not PackedStripBytes(bytes.size()) long. Allocates nothing.
HorizonStripError PackStrip(std::span<const std::uint8_t> bytes, std::span<std::uint8_t> packed);
// The levels' centres as grey levels; kBadOutputSize when `packed` is not
// PackedStripBytes(strip.size()) long. Allocates nothing.
HorizonStripError UnpackStrip(std::span<const std::uint8_t> packed, std::span<float> strip);

class HorizonStrip {
 public:
  // Projects every (azimuth, band row) through the lens and allocates the tap table. Not
  // for the frame path.
  HorizonStripError Init(const Lens& lens, const HorizonStripOptions& options);

  // Fills strip[0..n_azimuth) from the frame. Allocates nothing.
  HorizonStripError Extract(const ImageView& image, std::span<float> strip) const;

  int n_azimuth() const { return n_azimuth_; }
  const HorizonStripOptions& options() const { return options_; }
  // Fraction of (azimuth, band row) taps the camera sees.
  double visible_fraction() const { return visible_fraction_; }
  // Columns whose taps are all invisible (they read 0).
  int empty_columns() const { return empty_columns_; }

 private:
  struct Tap {
    std::uint16_t x;
    std::uint16_t y;
  };

  template <PixelFormat kFormat>
  void Gather(const ImageView& image, std::span<float> strip) const;

  HorizonStripOptions options_;
  int width_ = 0;
  int height_ = 0;
  int n_azimuth_ = 0;
  int empty_columns_ = 0;
  double visible_fraction_ = 0.0;
  std::vector<Tap> taps_;                  // visible taps, column after column
  std::vector<std::uint32_t> column_end_;  // taps of column j: [end[j-1], end[j])
  std::vector<float> column_weight_;       // 1 / visible taps (0 when none)
};

}  // namespace skyloc::dsp
