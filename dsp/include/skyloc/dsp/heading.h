// The heading of a recognised place: how far the robot is turned from the view
// a route frame was taught with, from the two frames' horizon strips (horizon_strip.h),
// two ways:
//   (b) circular cross-correlation of the whole strips (strip_alignment.h): the main
//       estimate; every column counts, so it needs no features;
//   (a) 1D SURF features + nearest neighbours + RANSAC (surf1d.h): the second estimate,
//       from the landmarks alone.
// Both give how far the query strip's content is turned from the stored one towards
// increasing azimuth; the robot turned the other way, so the heading is its negative:
//
//   heading_deg = the robot's yaw now minus its yaw when the frame was taught,
//                 counter-clockwise seen from above positive, in [-180, 180)
//
// (the sense of a pose's yaw; a robot that turned left by 25 degrees reads +25). The
// firmware (app::Pipeline), `skyloc eval` and `skyloc experiment heading` all estimate
// through this class, so they measure the same thing.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/surf1d.h"

namespace skyloc::dsp {

struct HeadingOptions {
  bool surf = true;  // also estimate (a); false skips its cost
  Surf1dOptions features;
  LandmarkMatchOptions matching;
  int max_features = 256;  // per strip; the strongest are kept
  // (a) answers only when RANSAC's line has at least this many inliers: a model from a
  // handful of matches is as often a wrong line (docs/RESULTS.md, "Heading": on the
  // manoeuvre runs, models with fewer than 10 inliers hold most of the errors above 10
  // degrees).
  int min_surf_inliers = 10;

  bool operator==(const HeadingOptions&) const = default;
};

struct HeadingEstimate {
  bool has_correlation = false;  // (b) gave a heading (false: a flat strip)
  double correlation_deg = 0;
  float confidence = 0;   // (b)'s peak correlation, clamped to 0..1
  float runner_up = 0;    // (b)'s best correlation away from the peak (ambiguity)
  bool has_surf = false;  // (a) found a RANSAC model with at least min_surf_inliers
  double surf_deg = 0;
  int surf_inliers = 0;
};

enum class HeadingError : std::uint8_t {
  kOk,
  kBadOptions,    // 1D SURF's options, max_features or min_surf_inliers (>= 2) out of
                  // range, or the strip is
                  // too short for its widest filter (more than 147 columns)
  kSizeMismatch,  // a strip is not the length given to Init
};

const char* HeadingErrorMessage(HeadingError error);

// Wraps degrees to [-180, 180).
double WrapDegrees(double degrees);

class HeadingEstimator {
 public:
  // Sizes the feature buffers for strips of `columns`. Not for the frame path.
  HeadingError Init(int columns, const HeadingOptions& options);

  // The heading of `test` relative to `stored` (both `columns` long, the same strip
  // options). Allocates nothing.
  HeadingError Estimate(std::span<const float> stored, std::span<const float> test,
                        HeadingEstimate* out);

  int columns() const { return columns_; }

 private:
  HeadingOptions options_;
  int columns_ = 0;
  Surf1d surf_;
  LandmarkMatcher matcher_;
  std::vector<Surf1dFeature> stored_features_;
  std::vector<Surf1dFeature> test_features_;
};

}  // namespace skyloc::dsp
