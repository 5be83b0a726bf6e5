#include "skyloc/dsp/heading.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "skyloc/dsp/strip_alignment.h"

namespace skyloc::dsp {

const char* HeadingErrorMessage(HeadingError error) {
  switch (error) {
    case HeadingError::kOk:
      return "ok";
    case HeadingError::kBadOptions:
      return "heading options out of range: the strip needs more than 147 columns for 1D "
             "SURF's widest filter, max_features must be 1..4096 and min_surf_inliers at "
             "least 2";
    case HeadingError::kSizeMismatch:
      return "a horizon strip is not the length the heading estimator was set up for";
  }
  return "unknown heading error";
}

double WrapDegrees(double degrees) {
  double d = std::fmod(degrees + 180.0, 360.0);
  if (d < 0)
    d += 360.0;
  return d - 180.0;
}

bool CorrelationUncertain(const StripAlignment& alignment) {
  const double sigma = static_cast<double>(alignment.noise);
  const double peak = std::clamp(static_cast<double>(alignment.correlation), 0.0, 1.0);
  const double unrelated = std::sqrt(1.0 - peak * peak);  // the part the turn leaves out
  // A tie within float rounding of c (a periodic skyline turned exactly) is uncertain too.
  constexpr double kRounding = 1e-6;
  return peak - static_cast<double>(alignment.second_peak) <=
         std::max(kUncertainSigmas * std::sqrt(2.0) * unrelated * sigma, kRounding);
}

HeadingError HeadingEstimator::Init(int columns, const HeadingOptions& options) {
  columns_ = 0;
  if (columns < 3 || options.max_features < 1 || options.max_features > 4096 ||
      options.min_surf_inliers < 2)
    return HeadingError::kBadOptions;
  if (options.surf) {
    if (surf_.Init(columns, options.features) != Surf1dError::kOk ||
        matcher_.Init(options.max_features, options.matching) != Surf1dError::kOk)
      return HeadingError::kBadOptions;
    stored_features_.assign(static_cast<std::size_t>(options.max_features), {});
    test_features_.assign(static_cast<std::size_t>(options.max_features), {});
  }
  if (!correlator_.Init(columns))
    return HeadingError::kBadOptions;
  features_held_ = false;
  options_ = options;
  columns_ = columns;
  return HeadingError::kOk;
}

HeadingError HeadingEstimator::Estimate(std::span<const float> stored, std::span<const float> test,
                                        HeadingEstimate* out) {
  *out = {};
  const auto n = static_cast<std::size_t>(columns_);
  if (n == 0 || stored.size() != n || test.size() != n)
    return HeadingError::kSizeMismatch;
  // Both ways measure the query content's turn; the robot turned the other way.
  if (!correlator_.Holds(stored)) {
    (void)correlator_.SetStored(stored);  // a flat strip: Align says so below
    features_held_ = false;
  }
  StripAlignment alignment;
  out->uncertain = true;  // a flat strip: nothing to stand out
  if (correlator_.Align(test, &alignment) == StripAlignmentError::kOk) {
    out->has_correlation = true;
    out->correlation_deg = WrapDegrees(-alignment.heading_offset_deg);
    out->confidence = std::clamp(alignment.correlation, 0.0f, 1.0f);
    out->runner_up = alignment.runner_up;
    out->noise = alignment.noise;
    out->uncertain = CorrelationUncertain(alignment);
    out->has_heading = true;
    out->heading_deg = out->correlation_deg;
  }
  if (!options_.surf || !(out->uncertain || options_.surf_every_frame))
    return HeadingError::kOk;
  out->surf_ran = true;
  if (!features_held_) {
    int stored_count = 0;
    features_held_ =
        surf_.Detect(stored, stored_features_, &stored_count) == Surf1dError::kOk &&
        matcher_.SetStored(std::span<const Surf1dFeature>(stored_features_)
                               .first(static_cast<std::size_t>(stored_count))) == Surf1dError::kOk;
    if (!features_held_)
      return HeadingError::kOk;
  }
  int test_count = 0;
  LandmarkMatch match;
  if (surf_.Detect(test, test_features_, &test_count) == Surf1dError::kOk &&
      matcher_.MatchStored(std::span<const Surf1dFeature>(test_features_)
                               .first(static_cast<std::size_t>(test_count)),
                           columns_, &match) == Surf1dError::kOk &&
      match.model_found && match.inliers >= options_.min_surf_inliers) {
    out->has_surf = true;
    out->surf_deg = WrapDegrees(-match.heading_offset_deg);
    out->surf_inliers = match.inliers;
  }
  return HeadingError::kOk;
}

}  // namespace skyloc::dsp
