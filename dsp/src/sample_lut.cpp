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
  // Offsets into the sky plane and its padding are 32-bit.
  if (width_ > 0xffff || height_ > 0xffff ||
      (static_cast<std::uint64_t>(width_) + 1) * static_cast<std::uint64_t>(height_ + 1) >=
          0xffffffffu)
    return SampleLutError::kSizeMismatch;
  unseen_offset_ = static_cast<std::uint32_t>(width_) * static_cast<std::uint32_t>(height_);
  rings_ = static_cast<int>(ring_theta.size());
  n_phi_ = n_phi;
  taps_per_sample_ = k * k;
  tap_weight_ = 1.0f / static_cast<float>(taps_per_sample_);
  taps_.assign(size() * static_cast<std::size_t>(taps_per_sample_), UnseenTap());

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
          *out = Tap{static_cast<std::uint32_t>(y) * static_cast<std::uint32_t>(width_) +
                         static_cast<std::uint32_t>(x),
                     0, 0, 1, 0};
        }
      }
    }
  }
  visible_fraction_ = static_cast<double>(visible) / static_cast<double>(size());
  PlanRuns(lens, taps_);
  return SampleLutError::kOk;
}

SampleLut::Tap SampleLut::BilinearTap(const Lens& lens, double px, double py) const {
  const int width = lens.params().width;
  const int height = lens.params().height;
  if (width < 2 || height < 2)
    return UnseenTap();
  const bool wraps = lens.params().model == LensModel::kEquirectangular;
  if (wraps)
    px = std::fmod(std::fmod(px, width) + width, width);
  Eigen::Vector3d ray;
  auto nx = static_cast<int>(std::lround(px));
  if (wraps)
    nx %= width;
  const auto ny = static_cast<int>(std::lround(py));
  if (nx < 0 || ny < 0 || nx >= width || ny >= height || !lens.PixelToCameraRay(nx, ny, &ray))
    return UnseenTap();
  // The block stays inside the image: a position within half a pixel of the border reads
  // the border pixels (on an equirectangular image's seam, the last column's value
  // continues to its edge instead of wrapping: half a pixel of one column).
  const double fx = std::clamp(px, 0.0, width - 1.0);
  const double fy = std::clamp(py, 0.0, height - 1.0);
  const int x0 = std::min(static_cast<int>(fx), width - 2);
  const int y0 = std::min(static_cast<int>(fy), height - 2);
  // Which of the block's pixels the camera sees is the sky plane's business (PlanRuns).
  return Tap{static_cast<std::uint32_t>(y0) * static_cast<std::uint32_t>(width) +
                 static_cast<std::uint32_t>(x0),
             static_cast<std::uint8_t>(std::min(255.0, std::floor((fx - x0) * 256.0))),
             static_cast<std::uint8_t>(std::min(255.0, std::floor((fy - y0) * 256.0))), 1, 0};
}

void SampleLut::PlanRuns(const Lens& lens, std::span<const Tap> taps) {
  const auto width = static_cast<std::size_t>(width_);
  const auto height = static_cast<std::size_t>(height_);
  const std::size_t plane = width * height;
  // Per row, the first and the last pixel a tap reads.
  std::vector<std::size_t> first(height, width), last(height, 0);
  auto read = [&](std::size_t offset) {
    if (offset >= plane)
      return;
    const std::size_t y = offset / width, x = offset % width;
    first[y] = std::min(first[y], x);
    last[y] = std::max(last[y], x);
  };
  const bool bilinear = taps_per_sample_ == 1;
  for (const Tap& tap : taps) {
    if (tap.seen == 0)
      continue;
    read(tap.offset);
    if (bilinear) {
      read(tap.offset + 1);
      read(tap.offset + width);
      read(tap.offset + width + 1);
    }
  }
  // Between them, the runs of pixels the camera sees: one a row for every lens model (its
  // view is convex along a row), but nothing here relies on it.
  runs_.clear();
  Eigen::Vector3d ray;
  for (std::size_t y = 0; y < height; ++y) {
    Run run;
    for (std::size_t x = first[y]; x <= last[y] && x < width; ++x) {
      if (lens.PixelToCameraRay(static_cast<int>(x), static_cast<int>(y), &ray)) {
        if (run.length == 0)
          run = Run{static_cast<std::uint16_t>(x), static_cast<std::uint16_t>(y), 0};
        ++run.length;
      } else if (run.length > 0) {
        runs_.push_back(run);
        run = Run{};
      }
    }
    if (run.length > 0)
      runs_.push_back(run);
  }
  sky_.assign(plane + width + 2, 0);
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
                UnseenTap());
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
  // Every frame's taps come from the table.
  PlanRuns(lens, table_);
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
      t = UnseenTap();
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
      *tap = UnseenTap();
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

template <typename RunIsSky>
void SampleLut::Threshold(const ImageView& image, std::size_t pixel_bytes,
                          const RunIsSky& run_is_sky) {
  std::uint8_t* const plane = sky_.data();
  const auto width = static_cast<std::size_t>(width_);
  for (const Run& run : runs_)
    run_is_sky(image.Row(run.y) + run.x * pixel_bytes, plane + run.y * width + run.x,
               static_cast<std::size_t>(run.length));
}

void SampleLut::Gather(std::span<float> samples) const {
  const std::uint8_t* const sky = sky_.data();
  const Tap* tap = taps_.data();
  if (taps_per_sample_ == 1) {
    // top = a (1 - fx) + b fx, bottom likewise, s = top (1 - fy) + bottom fy, in units of
    // 1/65536: at most 65536, exact in an int and in a float.
    const auto width = static_cast<std::size_t>(width_);
    constexpr float kUnit = 1.0f / 65536.0f;
    for (float& s : samples) {
      const std::uint8_t* p = sky + tap->offset;
      const int a = p[0];
      const int b = p[1];
      const int c = p[width];
      const int d = p[width + 1];
      const int fx = tap->fx;
      const int top = a * 256 + (b - a) * fx;
      const int bottom = c * 256 + (d - c) * fx;
      s = static_cast<float>(top * 256 + (bottom - top) * tap->fy) * kUnit;
      ++tap;
    }
    return;
  }
  for (float& s : samples) {
    int count = 0;
    for (int t = 0; t < taps_per_sample_; ++t, ++tap)
      count += sky[tap->offset];
    s = static_cast<float>(count) * tap_weight_;
  }
}

SampleLutError SampleLut::SampleMask(const ImageView& mask, std::span<float> samples) {
  if (mask.width != width_ || mask.height != height_ || mask.data == nullptr ||
      mask.format != PixelFormat::kGrey8)
    return SampleLutError::kSizeMismatch;
  if (samples.size() != size())
    return SampleLutError::kBadOutputSize;
  Threshold(mask, 1, [](const std::uint8_t* in, std::uint8_t* out, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
      out[i] = in[i] != 0 ? 1 : 0;
  });
  Gather(samples);
  return SampleLutError::kOk;
}

SampleLutError SampleLut::SampleImage(const ImageView& image, int threshold,
                                      std::span<float> samples) {
  if (image.width != width_ || image.height != height_ || image.data == nullptr)
    return SampleLutError::kSizeMismatch;
  if (samples.size() != size())
    return SampleLutError::kBadOutputSize;
  // Byte-wide comparisons (the loops vectorise): a threshold of 255 or more finds no sky.
  const auto t = static_cast<std::uint8_t>(std::clamp(threshold, 0, 255));
  switch (image.format) {
    case PixelFormat::kGrey8:
      Threshold(image, 1, [t](const std::uint8_t* in, std::uint8_t* out, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i)
          out[i] = in[i] > t ? 1 : 0;
      });
      break;
    case PixelFormat::kRgb24:
    case PixelFormat::kBgr24: {
      // (r + g + b) / 3 > t, in integers: r + g + b > 3 t + 2.
      const unsigned sum_t = 3u * t + 2u;
      Threshold(image, 3, [sum_t](const std::uint8_t* in, std::uint8_t* out, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i)
          out[i] = unsigned{in[3 * i]} + in[3 * i + 1] + in[3 * i + 2] > sum_t ? 1 : 0;
      });
      break;
    }
    case PixelFormat::kYuyv:
      Threshold(image, 2, [t](const std::uint8_t* in, std::uint8_t* out, std::size_t n) {
        for (std::size_t i = 0; i < n; ++i)
          out[i] = in[2 * i] > t ? 1 : 0;
      });
      break;
  }
  Gather(samples);
  return SampleLutError::kOk;
}

}  // namespace skyloc::dsp
