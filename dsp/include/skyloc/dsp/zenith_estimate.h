// The zenith from the image alone: with no attitude source, estimate the
// world's zenith in the body frame from the sky samples the descriptor already has
// (SkyDescriptor::samples(), on its grid), for the gravity-aligned cap.
// docs/SKY_DESCRIPTOR.md, "Tilt without an attitude source", has the method and the numbers.
//
//   ZenithEstimator estimator;
//   estimator.Init(descriptor.grid(), ZenithEstimateOptions{});   // allocates (start-up)
//   Attitude up;
//   if (estimator.Estimate(descriptor.samples(), timestamp_ns, &up)) ...  // no allocation
//
// Two methods:
//   kSkylinePlane: the skyline's mean plane. Along every meridian of the grid, the crossings
//     between sky and ground (sample value across 0.5, interpolated) are the skyline; the
//     zenith is the normal of the plane n.d = c fitted to them by least squares (the
//     eigenvector of their covariance with the smallest eigenvalue, weighted by sin theta).
//     In open terrain the skyline is the horizon, a small circle about the zenith, and the
//     fit is exact; obstacles on one side (a wall, a tree) tilt the plane towards them.
//   kSkyCentroid: the direction of the sky-weighted mean of the sample directions,
//     re-computed `iterations` times within `cone_deg` of the previous estimate (the first
//     pass about the body's z axis). Biased towards the body's z axis where the grid's edge
//     crops the sky, and towards the open side of an asymmetric scene.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/imu.h"
#include "skyloc/dsp/sh_grid.h"

namespace skyloc::dsp {

enum class ZenithMethod : std::uint8_t { kSkylinePlane, kSkyCentroid };

struct ZenithEstimateOptions {
  ZenithMethod method = ZenithMethod::kSkylinePlane;
  // kSkylinePlane: only the first sky-to-ground crossing going down each meridian from the
  // body's zenith (the outline of the sky around the zenith) when true; every crossing
  // (holes in a canopy as well) when false.
  bool first_crossing_only = true;
  // kSkyCentroid: re-centring passes and the cone they average over.
  int iterations = 3;
  double cone_deg = 60;
  // The estimate is rejected (Estimate returns false) beyond this tilt from the body's z.
  double max_tilt_deg = 75;
};

class ZenithEstimator {
 public:
  // Tables of the grid's directions. False when the grid is not initialised or options are
  // out of range (iterations 1..10, cone 10..90 degrees, max tilt 0..90).
  bool Init(const ShGrid& grid, const ZenithEstimateOptions& options);

  // samples: the grid's samples, ring-major (0 ground .. 1 sky). False (and *out untouched)
  // when the samples do not fit the grid, too few crossings or too little sky to fit, or
  // the fit lies beyond max_tilt_deg. Allocates nothing.
  bool Estimate(std::span<const float> samples, std::int64_t timestamp_ns, Attitude* out) const;

  const ZenithEstimateOptions& options() const { return options_; }

 private:
  bool SkylinePlane(std::span<const float> samples, std::array<double, 3>* up) const;
  bool SkyCentroid(std::span<const float> samples, std::array<double, 3>* up) const;

  ZenithEstimateOptions options_;
  int rings_ = 0;
  int n_phi_ = 0;
  std::vector<double> cos_phi_, sin_phi_;
  std::vector<double> ring_theta_, ring_weight_;
};

}  // namespace skyloc::dsp
