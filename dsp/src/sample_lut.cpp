#include "skyloc/dsp/sample_lut.h"

#include <algorithm>
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
  if (width_ > 0xffff || height_ > 0xffff)
    return SampleLutError::kSizeMismatch;
  rings_ = static_cast<int>(ring_theta.size());
  n_phi_ = n_phi;
  taps_per_sample_ = k * k;
  tap_weight_ = 1.0f / static_cast<float>(taps_per_sample_);
  taps_.assign(size() * static_cast<std::size_t>(taps_per_sample_), Tap{});

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
      Tap* out = &taps_[(static_cast<std::size_t>(i) * static_cast<std::size_t>(n_phi_) +
                         static_cast<std::size_t>(j)) *
                        static_cast<std::size_t>(taps_per_sample_)];
      if (k == 1) {
        *out = BilinearTap(lens, px, py);
        visible += out->seen != 0 ? 1 : 0;
        continue;
      }
      ++visible;
      const auto cx = static_cast<int>(std::lround(px));
      const auto cy = static_cast<int>(std::lround(py));
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
          *out = Tap{static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), 0, 0, 1, 0};
        }
      }
    }
  }
  visible_fraction_ = static_cast<double>(visible) / static_cast<double>(size());
  return SampleLutError::kOk;
}

SampleLut::Tap SampleLut::BilinearTap(const Lens& lens, double px, double py) {
  const int width = lens.params().width;
  const int height = lens.params().height;
  if (width < 2 || height < 2)
    return Tap{};
  const bool wraps = lens.params().model == LensModel::kEquirectangular;
  if (wraps)
    px = std::fmod(std::fmod(px, width) + width, width);
  Eigen::Vector3d ray;
  auto nx = static_cast<int>(std::lround(px));
  if (wraps)
    nx %= width;
  const auto ny = static_cast<int>(std::lround(py));
  if (nx < 0 || ny < 0 || nx >= width || ny >= height || !lens.PixelToCameraRay(nx, ny, &ray))
    return Tap{};
  // The block stays inside the image: a position within half a pixel of the border reads
  // the border pixels (on an equirectangular image's seam, the last column's value
  // continues to its edge instead of wrapping: half a pixel of one column).
  const double fx = std::clamp(px, 0.0, width - 1.0);
  const double fy = std::clamp(py, 0.0, height - 1.0);
  const int x0 = std::min(static_cast<int>(fx), width - 2);
  const int y0 = std::min(static_cast<int>(fy), height - 2);
  Tap tap{static_cast<std::uint16_t>(x0),
          static_cast<std::uint16_t>(y0),
          static_cast<std::uint8_t>(std::min(255.0, std::floor((fx - x0) * 256.0))),
          static_cast<std::uint8_t>(std::min(255.0, std::floor((fy - y0) * 256.0))),
          0,
          0};
  for (int b = 0; b < 4; ++b)
    if (lens.PixelToCameraRay(x0 + (b & 1), y0 + (b >> 1), &ray))
      tap.seen = static_cast<std::uint8_t>(tap.seen | (1 << b));
  return tap;
}

SampleLutError SampleLut::Init(const Lens& lens, const ShGrid& grid,
                               const SampleLutOptions& options) {
  std::vector<double> theta;
  theta.reserve(grid.rings().size());
  for (const ShRing& ring : grid.rings())
    theta.push_back(ring.theta);
  return Init(lens, theta, grid.longitudes(), options);
}

namespace {
// The oriented table's size: 512 x 512 cells of 8 bytes (2 MiB). Over a 185 degree lens a
// cell spans 0.47 degrees at the zenith and 0.23 at the horizon; a direction takes its
// cell centre's sub-pixel position, so it is placed to within half that (0.12-0.24
// degrees): a third of a pixel of a 640 x 480 frame (0.39 degrees), a sixth at 160 x 120.
constexpr int kOrientedTableCells = 512;
// Directions farther than this from the body zenith are not tabulated (the stereographic
// scale grows as tan(theta / 2)); a tilt leaves the world hemisphere within 90 + tilt.
constexpr double kOrientedMaxTheta = 120.0 * std::numbers::pi / 180.0;
}  // namespace

SampleLutError SampleLut::InitOriented(const Lens& lens, const ShGrid& grid,
                                       const SampleLutOptions& options) {
  if (options.footprint != 1)
    return SampleLutError::kBadFootprint;
  if (const SampleLutError e = Init(lens, grid, options); e != SampleLutError::kOk)
    return e;
  const double theta_max = std::min(lens.max_theta(), kOrientedMaxTheta);
  table_cells_ = kOrientedTableCells;
  const double rho = std::tan(theta_max / 2.0);
  const double scale = table_cells_ / (2.0 * rho);
  table_rho_ = static_cast<float>(rho);
  table_scale_ = static_cast<float>(scale);
  table_.assign(static_cast<std::size_t>(table_cells_) * static_cast<std::size_t>(table_cells_),
                Tap{});
  for (int b = 0; b < table_cells_; ++b) {
    const double v = (b + 0.5) / scale - rho;
    for (int a = 0; a < table_cells_; ++a) {
      const double u = (a + 0.5) / scale - rho;
      // The inverse stereographic projection of the cell's centre.
      const double r2 = u * u + v * v;
      const Eigen::Vector3d d(2.0 * u, 2.0 * v, 1.0 - r2);
      if (r2 > rho * rho)
        continue;
      double px = 0.0, py = 0.0;
      if (!lens.RayToPixel(d / (1.0 + r2), &px, &py))
        continue;
      table_[static_cast<std::size_t>(b) * static_cast<std::size_t>(table_cells_) +
             static_cast<std::size_t>(a)] = BilinearTap(lens, px, py);
    }
  }
  ring_sin_.resize(static_cast<std::size_t>(grid.ring_count()));
  ring_cos_.resize(static_cast<std::size_t>(grid.ring_count()));
  for (int i = 0; i < grid.ring_count(); ++i) {
    ring_sin_[static_cast<std::size_t>(i)] = static_cast<float>(grid.ring(i).sin_theta);
    ring_cos_[static_cast<std::size_t>(i)] = static_cast<float>(grid.ring(i).cos_theta);
  }
  cos_phi_.resize(static_cast<std::size_t>(n_phi_));
  sin_phi_.resize(static_cast<std::size_t>(n_phi_));
  for (int j = 0; j < n_phi_; ++j) {
    cos_phi_[static_cast<std::size_t>(j)] = static_cast<float>(std::cos(grid.phi(j)));
    sin_phi_[static_cast<std::size_t>(j)] = static_cast<float>(std::sin(grid.phi(j)));
  }
  meridian_.assign(3 * static_cast<std::size_t>(n_phi_), 0.0f);
  Orient({0.0, 0.0, 1.0});
  return SampleLutError::kOk;
}

void SampleLut::Orient(const std::array<double, 3>& up) {
  // Q = c I + [k]x + k k^T / (1 + c), k = z x up = (-uy, ux, 0), c = uz (Rodrigues); its
  // columns are the world x, y and z axes in the body frame. Upside down (c = -1) it is not
  // defined and nothing of the world's upper hemisphere is in view: every tap unseen.
  const double ux = up[0], uy = up[1], uz = up[2];
  if (!(uz > -1.0 + 1e-6)) {
    for (Tap& t : taps_)
      t = Tap{};
    return;
  }
  const double h = 1.0 / (1.0 + uz);
  const float qx[3] = {static_cast<float>(uz + uy * uy * h), static_cast<float>(-ux * uy * h),
                       static_cast<float>(-ux)};
  const float qy[3] = {static_cast<float>(-ux * uy * h), static_cast<float>(uz + ux * ux * h),
                       static_cast<float>(-uy)};
  const float qz[3] = {static_cast<float>(ux), static_cast<float>(uy), static_cast<float>(uz)};
  const auto n_phi = static_cast<std::size_t>(n_phi_);
  for (std::size_t j = 0; j < n_phi; ++j)
    for (std::size_t k = 0; k < 3; ++k)
      meridian_[3 * j + k] = cos_phi_[j] * qx[k] + sin_phi_[j] * qy[k];
  const auto cells = static_cast<std::size_t>(table_cells_);
  Tap* tap = taps_.data();
  for (std::size_t i = 0; i < ring_sin_.size(); ++i) {
    const float st = ring_sin_[i];
    const float zx = ring_cos_[i] * qz[0];
    const float zy = ring_cos_[i] * qz[1];
    const float zz = ring_cos_[i] * qz[2];
    for (std::size_t j = 0; j < n_phi; ++j, ++tap) {
      const float bx = st * meridian_[3 * j] + zx;
      const float by = st * meridian_[3 * j + 1] + zy;
      const float bz = st * meridian_[3 * j + 2] + zz;
      *tap = Tap{};
      if (!(bz > -0.99f))
        continue;
      const float s = table_scale_ / (1.0f + bz);
      // Cell index: (stereographic coordinate + rho) * scale, floored.
      const float a = bx * s + table_rho_ * table_scale_;
      const float b = by * s + table_rho_ * table_scale_;
      if (!(a >= 0.0f && b >= 0.0f && a < static_cast<float>(table_cells_) &&
            b < static_cast<float>(table_cells_)))
        continue;
      *tap = table_[static_cast<std::size_t>(b) * cells + static_cast<std::size_t>(a)];
    }
  }
}

void SampleLut::FillUnseenFromAbove(std::span<float> samples) const {
  const auto n_phi = static_cast<std::size_t>(n_phi_);
  for (std::size_t s = 0; s < samples.size() && s < taps_.size(); ++s)
    if (taps_[s].seen == 0)
      samples[s] = s < n_phi ? 0.0f : samples[s - n_phi];
}

template <typename Predicate>
void SampleLut::Gather(const ImageView& image, const Predicate& is_sky,
                       std::span<float> samples) const {
  const Tap* tap = taps_.data();
  if (taps_per_sample_ == 1) {
    // Bilinear between the 2 x 2 pixels around the sub-pixel position; unseen pixels are
    // ground. fx, fy are multiples of 1/256, so an all-sky block reads exactly 1.
    constexpr float kInv = 1.0f / 256.0f;
    for (float& s : samples) {
      if (tap->seen == 0) {
        s = 0.0f;
        ++tap;
        continue;
      }
      const float fx = static_cast<float>(tap->fx) * kInv;
      const float fy = static_cast<float>(tap->fy) * kInv;
      const std::uint8_t* r0 = image.Row(tap->y);
      const std::uint8_t* r1 = image.Row(tap->y + 1);
      const std::uint16_t x0 = tap->x;
      const auto x1 = static_cast<std::uint16_t>(x0 + 1);
      const unsigned seen = tap->seen;
      const float top = ((seen & 1u) != 0 && is_sky(r0, x0) ? 1.0f - fx : 0.0f) +
                        ((seen & 2u) != 0 && is_sky(r0, x1) ? fx : 0.0f);
      const float bottom = ((seen & 4u) != 0 && is_sky(r1, x0) ? 1.0f - fx : 0.0f) +
                           ((seen & 8u) != 0 && is_sky(r1, x1) ? fx : 0.0f);
      s = top + fy * (bottom - top);
      ++tap;
    }
    return;
  }
  for (float& s : samples) {
    int sky = 0;
    for (int t = 0; t < taps_per_sample_; ++t, ++tap)
      sky += (tap->seen != 0 && is_sky(image.Row(tap->y), tap->x)) ? 1 : 0;
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
