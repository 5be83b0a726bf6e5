#include "skyloc/dsp/sample_lut.h"

#include <cmath>
#include <numbers>

namespace skyloc::dsp {

const char* SampleLutErrorMessage(SampleLutError error) {
  switch (error) {
    case SampleLutError::kOk:
      return "ok";
    case SampleLutError::kBadFootprint:
      return "the sample footprint must be an odd number of pixels from 1 to 7";
    case SampleLutError::kBadGrid:
      return "the sampling grid needs at least one ring in [0, pi] and one longitude";
    case SampleLutError::kSizeMismatch:
      return "the frame is not the size the camera file describes: fix width/height there";
    case SampleLutError::kBadOutputSize:
      return "the samples buffer must hold rings * longitudes floats";
  }
  return "unknown sample table error";
}

SampleLutError SampleLut::Init(const Lens& lens, std::span<const double> ring_theta, int n_phi,
                               const SampleLutOptions& options) {
  const int k = options.footprint;
  if (k < 1 || k > 7 || k % 2 == 0)
    return SampleLutError::kBadFootprint;
  if (ring_theta.empty() || n_phi < 1)
    return SampleLutError::kBadGrid;
  for (double t : ring_theta)
    if (!(t >= 0.0 && t <= std::numbers::pi))
      return SampleLutError::kBadGrid;
  width_ = lens.params().width;
  height_ = lens.params().height;
  if (width_ >= kInvisible || height_ >= kInvisible)
    return SampleLutError::kSizeMismatch;
  rings_ = static_cast<int>(ring_theta.size());
  n_phi_ = n_phi;
  taps_per_sample_ = k * k;
  tap_weight_ = 1.0f / static_cast<float>(taps_per_sample_);
  taps_.assign(size() * static_cast<std::size_t>(taps_per_sample_), Tap{0, kInvisible});

  const bool wraps = lens.params().model == LensModel::kEquirectangular;
  const int half = k / 2;
  std::size_t visible = 0;
  Eigen::Vector3d ray;
  for (int i = 0; i < rings_; ++i) {
    const double theta = ring_theta[static_cast<std::size_t>(i)];
    for (int j = 0; j < n_phi_; ++j) {
      const double phi = 2.0 * std::numbers::pi * j / n_phi_;
      const Eigen::Vector3d d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
      double px = 0.0, py = 0.0;
      if (!lens.RayToPixel(d, &px, &py))
        continue;
      ++visible;
      const auto cx = static_cast<int>(std::lround(px));
      const auto cy = static_cast<int>(std::lround(py));
      Tap* out = &taps_[(static_cast<std::size_t>(i) * static_cast<std::size_t>(n_phi_) +
                         static_cast<std::size_t>(j)) *
                        static_cast<std::size_t>(taps_per_sample_)];
      for (int dy = -half; dy <= half; ++dy) {
        for (int dx = -half; dx <= half; ++dx, ++out) {
          int x = cx + dx;
          const int y = cy + dy;
          if (wraps)
            x = (x % width_ + width_) % width_;
          if (x < 0 || y < 0 || x >= width_ || y >= height_)
            continue;
          // A tap is sky-capable only if the camera sees its pixel centre.
          if (!lens.PixelToCameraRay(x, y, &ray))
            continue;
          *out = Tap{static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y)};
        }
      }
    }
  }
  visible_fraction_ = static_cast<double>(visible) / static_cast<double>(size());
  return SampleLutError::kOk;
}

SampleLutError SampleLut::Init(const Lens& lens, const ShGrid& grid,
                               const SampleLutOptions& options) {
  std::vector<double> theta;
  theta.reserve(grid.rings().size());
  for (const ShRing& ring : grid.rings())
    theta.push_back(ring.theta);
  return Init(lens, theta, grid.longitudes(), options);
}

template <typename Predicate>
void SampleLut::Gather(const ImageView& image, const Predicate& is_sky,
                       std::span<float> samples) const {
  const Tap* tap = taps_.data();
  if (taps_per_sample_ == 1) {
    for (float& s : samples) {
      s = (tap->y != kInvisible && is_sky(image.Row(tap->y), tap->x)) ? 1.0f : 0.0f;
      ++tap;
    }
    return;
  }
  for (float& s : samples) {
    int sky = 0;
    for (int t = 0; t < taps_per_sample_; ++t, ++tap)
      sky += (tap->y != kInvisible && is_sky(image.Row(tap->y), tap->x)) ? 1 : 0;
    s = static_cast<float>(sky) * tap_weight_;
  }
}

SampleLutError SampleLut::SampleMask(const ImageView& mask, std::span<float> samples) const {
  if (mask.width != width_ || mask.height != height_ || mask.data == nullptr ||
      mask.format != PixelFormat::kGrey8)
    return SampleLutError::kSizeMismatch;
  if (samples.size() != size())
    return SampleLutError::kBadOutputSize;
  Gather(
      mask, [](const std::uint8_t* row, std::uint16_t x) { return row[x] != 0; }, samples);
  return SampleLutError::kOk;
}

SampleLutError SampleLut::SampleImage(const ImageView& image, int threshold,
                                      std::span<float> samples) const {
  if (image.width != width_ || image.height != height_ || image.data == nullptr)
    return SampleLutError::kSizeMismatch;
  if (samples.size() != size())
    return SampleLutError::kBadOutputSize;
  const auto t = static_cast<unsigned>(threshold < 0 ? 0 : threshold);
  switch (image.format) {
    case PixelFormat::kGrey8:
      Gather(
          image, [t](const std::uint8_t* row, std::uint16_t x) { return row[x] > t; }, samples);
      break;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24:
      Gather(
          image,
          [t](const std::uint8_t* row, std::uint16_t x) {
            const std::uint8_t* p = row + 3 * static_cast<std::size_t>(x);
            return (unsigned{p[0]} + p[1] + p[2]) / 3u > t;
          },
          samples);
      break;
    case PixelFormat::kYuyv:
      Gather(
          image,
          [t](const std::uint8_t* row, std::uint16_t x) {
            return row[2 * static_cast<std::size_t>(x)] > t;
          },
          samples);
      break;
  }
  return SampleLutError::kOk;
}

}  // namespace skyloc::dsp
