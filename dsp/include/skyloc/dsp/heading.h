// The heading of a recognised place: how far the robot is turned from the view
// a route frame was taught with, from the two frames' horizon strips (horizon_strip.h),
// two ways:
//   (b) circular cross-correlation of the whole strips by FFT (strip_alignment.h,
//       StripCorrelator): the main estimate; every column counts, so it needs no features;
//   (a) 1D SURF features + nearest neighbours + RANSAC (surf1d.h): the second estimate,
//       from the landmarks alone, run only when (b) is uncertain (below), where it can
//       change the answer: it costs about fifteen times (b).
// Both give how far the query strip's content is turned from the stored one towards
// increasing azimuth; the robot turned the other way, so the heading is its negative:
//
//   heading_deg = the robot's yaw now minus its yaw when the frame was taught,
//                 counter-clockwise seen from above positive, in [-180, 180)
//
// (the sense of a pose's yaw; a robot that turned left by 25 degrees reads +25).
//
// The answer (HeadingEstimate::heading_deg) is (b)'s; (a), the second opinion, runs only
// where (b) is uncertain. (Taking (a)'s heading there made the manoeuvre runs' 90th
// percentile worse, 2.1 -> 2.7 degrees on the repetitive road: docs/RESULTS.md.) (b) is
// uncertain when the best other local maximum of c (the competing turn)
// comes within chance of its peak. The model: the query strip is the stored one turned,
// times the peak correlation c*, plus a part unrelated to it, sqrt(1 - c*^2) of it; at
// every shift that part adds to c a chance term of standard deviation sigma
// (StripAlignment::noise, derived there). The peak minus the competing maximum is then
// what the strips' shape gives, plus the difference of two chance terms, of standard
// deviation sqrt(2) sqrt(1 - c*^2) sigma; (b) is uncertain when the gap is smaller than
// kUncertainSigmas of those. kUncertainSigmas = 3 is the conventional one-sided 0.13 %
// tail, not fitted to any run. A pure turn (c* = 1) is certain unless another turn fits
// as well (a periodic skyline); unrelated strips have a small gap and c* near 0. The
// firmware (app::Pipeline), `skyloc eval` and `skyloc experiment heading` all estimate
// through this class, so they measure the same thing.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/dsp/strip_alignment.h"
#include "skyloc/dsp/surf1d.h"

namespace skyloc::dsp {

struct HeadingOptions {
  bool surf = true;  // also estimate (a) where (b) is uncertain; false skips it always
  // (a) on every frame, whatever (b) says: for the evaluation tools, which measure (a)
  // alone; the answer (heading_deg) is the same either way.
  bool surf_every_frame = false;
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
  // The answer: (b)'s heading (has_heading = has_correlation).
  bool has_heading = false;
  double heading_deg = 0;
  bool uncertain = false;        // (b) did not stand out of chance (see above), or was flat
  bool surf_ran = false;         // (a) was run on this pair
  bool has_correlation = false;  // (b) gave a heading (false: a flat strip)
  double correlation_deg = 0;
  float confidence = 0;   // (b)'s peak correlation, clamped to 0..1
  float runner_up = 0;    // (b)'s best correlation away from the peak (ambiguity)
  float noise = 0;        // (b)'s chance level: StripAlignment::noise
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

// How many standard deviations of chance (b)'s peak must stand out by (see above).
inline constexpr double kUncertainSigmas = 3.0;

// Whether (b)'s alignment is uncertain, by the rule above.
bool CorrelationUncertain(const StripAlignment& alignment);

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
  // (b) by FFT; it holds the stored strip and its spectrum: a localised robot matches the
  // same route frame on many frames in a row, and the same strip, bit for bit, has the
  // same spectrum and the same features, so both are computed once.
  StripCorrelator correlator_;
  bool features_held_ = false;  // stored_features_ are the held strip's, in the matcher
};

}  // namespace skyloc::dsp
