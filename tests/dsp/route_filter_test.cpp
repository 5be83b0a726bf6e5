// The route filter (dsp/route_filter.h) against a second implementation written from
// docs/SEQSLAM.md in double precision with plain loops, against planted routes sampled in
// time (stops, 0.5x and 2x speed, a kidnap), and against the failure it replaces: the
// fixed-window contrast enhancement's basin-edge shift.
#include "skyloc/dsp/route_filter.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include "skyloc/dsp/localisation_state.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/platform/alloc_counter.h"

namespace skyloc::dsp {
namespace {

constexpr double kTwoPi = 6.283185307179586;

// A route's appearance as a smooth function of the distance travelled: each descriptor
// element is a sum of sinusoids of random wavelengths (metres), so neighbouring places
// look alike over about a metre and places far apart differ.
class AppearanceField {
 public:
  AppearanceField(int dim, unsigned seed, double min_wavelength_m = 3.0,
                  double max_wavelength_m = 15.0)
      : dim_(dim) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> wavelength(min_wavelength_m, max_wavelength_m),
        phase(0.0, kTwoPi);
    for (int i = 0; i < dim * kWaves; ++i) {
      wavelengths_.push_back(wavelength(rng));
      phases_.push_back(phase(rng));
    }
  }
  int dim() const { return dim_; }
  void At(double s_m, float noise, std::mt19937& rng, std::vector<float>* out) const {
    std::normal_distribution<float> gauss(0.0f, noise);
    for (int i = 0; i < dim_; ++i) {
      double x = 2.0 * kWaves;  // positive, like amplitudes
      for (int w = 0; w < kWaves; ++w) {
        const std::size_t k = static_cast<std::size_t>(i * kWaves + w);
        x += std::sin(kTwoPi * s_m / wavelengths_[k] + phases_[k]);
      }
      out->push_back(static_cast<float>(x) + (noise > 0 ? gauss(rng) : 0.0f));
    }
  }

 private:
  static constexpr int kWaves = 3;
  int dim_;
  std::vector<double> wavelengths_, phases_;
};

// A speed profile: (seconds, metres per second) pieces, sampled at a fixed frame rate.
struct Piece {
  double seconds;
  double speed_mps;
};

std::vector<double> SampleInTime(const std::vector<Piece>& profile, double fps, double start_m) {
  std::vector<double> s;
  double at = start_m;
  for (const Piece& p : profile) {
    const int frames = static_cast<int>(std::lround(p.seconds * fps));
    for (int i = 0; i < frames; ++i) {
      s.push_back(at);
      at += p.speed_mps / fps;
    }
  }
  return s;
}

struct TimedRun {
  std::vector<double> s_m;  // distance along the route of each frame
  std::vector<float> descriptors;
  int frames() const { return static_cast<int>(s_m.size()); }
  std::span<const float> Frame(int i, int dim) const {
    return std::span<const float>(descriptors)
        .subspan(static_cast<std::size_t>(i * dim), static_cast<std::size_t>(dim));
  }
};

TimedRun MakeRun(const AppearanceField& field, std::vector<double> s_m, float noise,
                 unsigned seed) {
  TimedRun run;
  run.s_m = std::move(s_m);
  std::mt19937 rng(seed);
  for (const double s : run.s_m)
    field.At(s, noise, rng, &run.descriptors);
  return run;
}

// The truth of a query: every reference frame tied for nearest in distance along the
// route (a stop holds many); a match is right within +-tolerance frames of them.
bool Within(const TimedRun& reference, double query_s, int matched, int tolerance) {
  double best = std::numeric_limits<double>::infinity();
  for (const double s : reference.s_m)
    best = std::min(best, std::abs(s - query_s));
  for (int r = 0; r < reference.frames(); ++r) {
    if (std::abs(reference.s_m[static_cast<std::size_t>(r)] - query_s) <= best + 1e-9 &&
        std::abs(r - matched) <= tolerance)
      return true;
  }
  return false;
}

::testing::AssertionResult Teach(RouteFilter& filter, const TimedRun& run, int dim) {
  for (int i = 0; i < run.frames(); ++i) {
    if (const SeqSlamError e = filter.AddReference(run.Frame(i, dim)); e != SeqSlamError::kOk)
      return ::testing::AssertionFailure() << "frame " << i << ": " << SeqSlamErrorMessage(e);
  }
  if (const SeqSlamError e = filter.FinishRoute(); e != SeqSlamError::kOk)
    return ::testing::AssertionFailure() << SeqSlamErrorMessage(e);
  return ::testing::AssertionSuccess();
}

std::vector<SeqSlamMatch> Repeat(RouteFilter& filter, const TimedRun& run, int dim) {
  std::vector<SeqSlamMatch> matches(static_cast<std::size_t>(run.frames()));
  for (int t = 0; t < run.frames(); ++t)
    EXPECT_EQ(filter.Step(run.Frame(t, dim), &matches[static_cast<std::size_t>(t)]),
              SeqSlamError::kOk);
  return matches;
}

// ---- The second implementation -----------------------------------------------------
// Written from docs/SEQSLAM.md ("The route filter"), not from route_filter.cpp: doubles,
// whole matrices, every sum spelled out.

double MeanAbsDifference(std::span<const float> a, std::span<const float> b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i)
    sum += std::abs(static_cast<double>(a[i]) - static_cast<double>(b[i]));
  return sum / static_cast<double>(a.size());
}

struct NaiveResult {
  std::vector<int> first, last;  // frames merged into each row
  std::vector<int> row, reference;
  std::vector<double> confidence;
  std::vector<double> gap;  // best cost against the next lowest cost of any row
};

// `compared` (the search window, docs/SEQSLAM.md): compared[t][r] says whether row r's
// difference is computed at frame t; the others keep their last value. Null: every row.
NaiveResult NaiveFilter(const TimedRun& reference, const TimedRun& query, int dim,
                        const RouteFilterParams& p,
                        const std::vector<std::vector<bool>>* compared = nullptr) {
  NaiveResult out;
  const int n = reference.frames();
  // Keyframes: the 10th percentile (index floor((n - 1) / 10) of the sorted consecutive
  // differences) times the factor, at most half the median (index floor((n - 1) / 2)); a
  // frame joins a row while within it of the row's first.
  double threshold = -1;
  if (p.keyframe_noise_factor > 0 && n >= 2) {
    std::vector<double> consecutive;
    for (int i = 1; i < n; ++i)
      consecutive.push_back(
          MeanAbsDifference(reference.Frame(i - 1, dim), reference.Frame(i, dim)));
    std::sort(consecutive.begin(), consecutive.end());
    threshold = std::min(static_cast<double>(p.keyframe_noise_factor) *
                             consecutive[static_cast<std::size_t>((n - 1) / 10)],
                         0.5 * consecutive[static_cast<std::size_t>((n - 1) / 2)]);
  }
  out.first.push_back(0);
  out.last.push_back(0);
  for (int i = 1; i < n; ++i) {
    const double d =
        MeanAbsDifference(reference.Frame(out.first.back(), dim), reference.Frame(i, dim));
    if (d <= threshold) {
      out.last.back() = i;
    } else {
      out.first.push_back(i);
      out.last.push_back(i);
    }
  }
  const int rows = static_cast<int>(out.first.size());
  const double lambda = 1.0 - 1.0 / p.sequence_length;
  std::vector<double> cost(static_cast<std::size_t>(rows), 0.0);
  int track_best = -1;   // the best row of the frame before
  int track_length = 0;  // frames the best row has continued its track, this one included
  std::vector<double> d(static_cast<std::size_t>(rows));
  for (int t = 0; t < query.frames(); ++t) {
    for (int r = 0; r < rows; ++r) {
      if (compared == nullptr ||
          (*compared)[static_cast<std::size_t>(t)][static_cast<std::size_t>(r)])
        d[static_cast<std::size_t>(r)] = MeanAbsDifference(
            reference.Frame(out.first[static_cast<std::size_t>(r)], dim), query.Frame(t, dim));
    }
    double mean = 0;
    for (const double v : d)
      mean += v / rows;
    double var = 0;
    for (const double v : d)
      var += (v - mean) * (v - mean) / rows;
    std::vector<double> next(static_cast<std::size_t>(rows));
    for (int r = 0; r < rows; ++r) {
      const double z = var > 0 ? (d[static_cast<std::size_t>(r)] - mean) / std::sqrt(var) : 0.0;
      double from = std::numeric_limits<double>::infinity();
      for (int k = 0; k <= p.max_advance; ++k) {
        if (r - k >= 0)
          from = std::min(from, t == 0 ? 0.0 : cost[static_cast<std::size_t>(r - k)]);
      }
      next[static_cast<std::size_t>(r)] = z + lambda * from;
    }
    cost = next;
    const int best = static_cast<int>(std::min_element(cost.begin(), cost.end()) - cost.begin());
    // The best's basin: the rows on either side while the cost does not fall, and at
    // least +-window/2; the runner-up is the lowest cost outside it.
    int lo = best, hi = best;
    while (lo > 0 && cost[static_cast<std::size_t>(lo - 1)] >= cost[static_cast<std::size_t>(lo)])
      --lo;
    while (hi + 1 < rows &&
           cost[static_cast<std::size_t>(hi + 1)] >= cost[static_cast<std::size_t>(hi)])
      ++hi;
    lo = std::min(lo, best - p.uniqueness_window / 2);
    hi = std::max(hi, best + p.uniqueness_window / 2);
    double second = std::numeric_limits<double>::infinity();
    double next_lowest = std::numeric_limits<double>::infinity();
    for (int r = 0; r < rows; ++r) {
      if (r != best)
        next_lowest = std::min(next_lowest, cost[static_cast<std::size_t>(r)]);
      if (r < lo || r > hi)
        second = std::min(second, cost[static_cast<std::size_t>(r)]);
    }
    out.row.push_back(best);
    // The reported frame: the mean row offset over the best row and its neighbours, with
    // weights exp(-(cost - best cost)), none past the route's ends, placed in the row's
    // run of frames.
    const auto weight = [&](int r) {
      return r < 0 || r >= rows ? 0.0
                                : std::exp(cost[static_cast<std::size_t>(best)] -
                                           cost[static_cast<std::size_t>(r)]);
    };
    const double offset =
        (weight(best + 1) - weight(best - 1)) / (weight(best - 1) + 1.0 + weight(best + 1));
    const int first = out.first[static_cast<std::size_t>(best)];
    const int last = out.last[static_cast<std::size_t>(best)];
    out.reference.push_back(first + static_cast<int>(std::floor((0.5 + offset) * (last - first))));
    // A best row that moved against the motion model (more than window/2 rows back, or
    // more than K + window/2 forward) starts a new track; a track's confidence is scaled by
    // its length over 2 ds frames, up to 1.
    const bool moved_as_allowed = track_best >= 0 &&
                                  best - track_best >= -p.uniqueness_window / 2 &&
                                  best - track_best <= p.max_advance + p.uniqueness_window / 2;
    track_length = moved_as_allowed ? track_length + 1 : 1;
    track_best = best;
    const double margin_confidence =
        std::isinf(second) ? 0.0 : 1.0 - std::exp(-(second - cost[static_cast<std::size_t>(best)]));
    out.confidence.push_back(margin_confidence *
                             std::min(1.0, track_length / (2.0 * p.sequence_length)));
    out.gap.push_back(next_lowest - cost[static_cast<std::size_t>(best)]);
  }
  return out;
}

struct Scenario {
  AppearanceField field{24, 7};
  TimedRun reference, query;
};

// Taught at 1 m/s with a 4 s stop at the start and one midway; repeated with a stop of
// its own elsewhere, then at 2x and at 0.5x the taught speed.
Scenario StopsAndSpeeds() {
  Scenario sc;
  sc.reference =
      MakeRun(sc.field, SampleInTime({{4, 0}, {30, 1.0}, {5, 0}, {30, 1.0}}, 10, 0.0), 0.02f, 11);
  sc.query = MakeRun(
      sc.field, SampleInTime({{3, 0}, {10, 1.0}, {6, 0}, {8, 2.0}, {20, 0.5}, {5, 1.0}}, 10, 0.0),
      0.02f, 12);
  return sc;
}

TEST(RouteFilter, EqualsTheNaiveImplementationEveryFrame) {
  for (const ReferenceStorage storage :
       {ReferenceStorage::kFloat32, ReferenceStorage::kBFloat16, ReferenceStorage::kCodes8}) {
    Scenario sc = StopsAndSpeeds();
    const int dim = sc.field.dim();
    // The naive filter sees the route as the engine stores it.
    if (storage == ReferenceStorage::kBFloat16) {
      for (float& v : sc.reference.descriptors)
        v = FromBFloat16(ToBFloat16(v));
    }
    if (storage == ReferenceStorage::kCodes8) {
      const auto d = static_cast<std::size_t>(dim);
      std::vector<std::uint8_t> codes(d);
      for (std::size_t at = 0; at < sc.reference.descriptors.size(); at += d) {
        const std::span<float> row(sc.reference.descriptors.data() + at, d);
        DecodeCodes<std::uint8_t>(codes, EncodeCodes<std::uint8_t>(row, codes), row);
      }
    }
    for (const int ds : {1, 4, 10}) {
      RouteFilterParams p;
      p.sequence_length = ds;
      RouteFilter filter;
      ASSERT_EQ(filter.Init(p, dim, sc.reference.frames(), storage), SeqSlamError::kOk);
      ASSERT_TRUE(Teach(filter, sc.reference, dim));
      const NaiveResult naive = NaiveFilter(sc.reference, sc.query, dim, p);
      ASSERT_EQ(filter.rows(), static_cast<int>(naive.first.size()));
      for (int r = 0; r < filter.rows(); ++r) {
        ASSERT_EQ(filter.row_first_frame(r), naive.first[static_cast<std::size_t>(r)]) << r;
        ASSERT_EQ(filter.row_last_frame(r), naive.last[static_cast<std::size_t>(r)]) << r;
      }
      const std::vector<SeqSlamMatch> m = Repeat(filter, sc.query, dim);
      int compared = 0;
      for (std::size_t t = 0; t < m.size(); ++t) {
        ASSERT_TRUE(m[t].valid);
        // Float and double may order two rows whose costs are within rounding (1e-4 of a
        // column standard deviation) either way; every other frame must agree exactly.
        if (naive.gap[t] < 1e-4)
          continue;
        ++compared;
        EXPECT_EQ(m[t].row, naive.row[t]) << "ds " << ds << " frame " << t;
        // The frame within a merged row comes from exp() of costs: float and double may
        // round its position across a frame boundary. A row of one frame is exact.
        const std::size_t row = static_cast<std::size_t>(naive.row[t]);
        const int slack = naive.first[row] == naive.last[row] ? 0 : 1;
        EXPECT_LE(std::abs(m[t].reference - naive.reference[t]), slack)
            << "ds " << ds << " frame " << t;
        EXPECT_NEAR(m[t].confidence, naive.confidence[t], 1e-4) << "ds " << ds << " frame " << t;
      }
      EXPECT_GT(compared, static_cast<int>(m.size()) * 9 / 10);
    }
  }
}

TEST(RouteFilter, MergesStopsIntoOneRowAndKeepsFramesInMotion) {
  const Scenario sc = StopsAndSpeeds();
  RouteFilter filter;
  ASSERT_EQ(filter.Init(RouteFilterParams{}, sc.field.dim(), sc.reference.frames()),
            SeqSlamError::kOk);
  ASSERT_TRUE(Teach(filter, sc.reference, sc.field.dim()));
  // 40 standing frames at the start, 300 moving, 50 standing, 300 moving. The stops are
  // noise only; in motion a frame moves 0.1 m, far above the noise: every one is kept.
  ASSERT_EQ(sc.reference.frames(), 690);
  EXPECT_EQ(filter.row_first_frame(0), 0);
  EXPECT_GE(filter.row_last_frame(0), 40);  // the start's stop (and maybe the next frame)
  EXPECT_LE(filter.row_last_frame(0), 41);
  int stop_rows = 0;
  for (int r = 0; r < filter.rows(); ++r) {
    const int span = filter.row_last_frame(r) - filter.row_first_frame(r);
    if (span > 1)
      ++stop_rows;
    EXPECT_LE(span, 51) << "row " << r;
  }
  EXPECT_EQ(stop_rows, 2);
  EXPECT_NEAR(filter.rows(), 690 - 40 - 50, 4);
  EXPECT_GT(filter.keyframe_threshold(), 0.0f);

  // Finishing again leaves the rows as they are (the slots hold rows now, not frames).
  const int rows = filter.rows();
  const int last_of_first = filter.row_last_frame(0);
  ASSERT_EQ(filter.FinishRoute(), SeqSlamError::kOk);
  EXPECT_EQ(filter.rows(), rows);
  EXPECT_EQ(filter.row_last_frame(0), last_of_first);

  // Factor 0 keeps every frame.
  RouteFilterParams keep;
  keep.keyframe_noise_factor = 0;
  RouteFilter all;
  ASSERT_EQ(all.Init(keep, sc.field.dim(), sc.reference.frames()), SeqSlamError::kOk);
  ASSERT_TRUE(Teach(all, sc.reference, sc.field.dim()));
  EXPECT_EQ(all.rows(), 690);
}

// Frames that look unrelated (a route sampled far apart): every consecutive difference
// is alike, the 10th percentile is no noise floor, and nothing may merge.
TEST(RouteFilter, UnrelatedFramesAreNeverMerged) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
  constexpr int kDim = 24, kFrames = 60;
  RouteFilter filter;
  ASSERT_EQ(filter.Init(RouteFilterParams{}, kDim, kFrames), SeqSlamError::kOk);
  std::vector<float> frame(kDim);
  for (int i = 0; i < kFrames; ++i) {
    for (float& v : frame)
      v = uniform(rng);
    ASSERT_EQ(filter.AddReference(frame), SeqSlamError::kOk);
  }
  ASSERT_EQ(filter.FinishRoute(), SeqSlamError::kOk);
  EXPECT_EQ(filter.rows(), kFrames);
}

TEST(RouteFilter, FollowsAPlantedRouteThroughStopsAndSpeedChanges) {
  const Scenario sc = StopsAndSpeeds();
  RouteFilter filter;
  ASSERT_EQ(filter.Init(RouteFilterParams{}, sc.field.dim(), sc.reference.frames()),
            SeqSlamError::kOk);
  ASSERT_TRUE(Teach(filter, sc.reference, sc.field.dim()));
  const std::vector<SeqSlamMatch> m = Repeat(filter, sc.query, sc.field.dim());
  // After the first ds frames of evidence, every frame within 5 frames of the truth:
  // through the query's stops, the 2x and the 0.5x stretch.
  int wrong = 0;
  for (int t = 10; t < sc.query.frames(); ++t) {
    if (!Within(sc.reference, sc.query.s_m[static_cast<std::size_t>(t)],
                m[static_cast<std::size_t>(t)].reference, 5)) {
      ++wrong;
      ADD_FAILURE() << "frame " << t << " at " << sc.query.s_m[static_cast<std::size_t>(t)]
                    << " m matched reference " << m[static_cast<std::size_t>(t)].reference;
    }
  }
  EXPECT_EQ(wrong, 0);
}

// A stop merged into one row spans many taught frames, and the first centimetres of the
// acceleration after it (they differ from the stop by less than the merge threshold).
// While a repeat arrives at the place or leaves it, the truth is a frame at one end of the
// row, up to half the row from its middle; the row must report the end the evidence
// points to (route_filter.h, 5.): the middle-frame rule misses those frames by 20 or more.
TEST(RouteFilter, AMergedStopReportsTheEndTheRobotArrivesAtOrLeavesBy) {
  const AppearanceField field(24, 7);
  // Taught: 10 m at 1 m/s, a 5 s stop, 1 s of pulling away at 1 cm a frame, 10 m more.
  const TimedRun reference =
      MakeRun(field, SampleInTime({{10, 1.0}, {5, 0}, {1, 0.1}, {10, 1.0}}, 10, 0.0), 0.02f, 51);
  // Repeats at 0.5 m/s from 7 m: through the place without stopping, and stopping there
  // for 3 s and pulling away as the taught run did.
  const std::vector<TimedRun> queries = {
      MakeRun(field, SampleInTime({{12, 0.5}}, 10, 7.0), 0.02f, 52),
      MakeRun(field, SampleInTime({{6, 0.5}, {3, 0}, {1, 0.1}, {6, 0.5}}, 10, 7.0), 0.02f, 53)};
  for (std::size_t q = 0; q < queries.size(); ++q) {
    const TimedRun& query = queries[q];
    RouteFilter filter;
    ASSERT_EQ(filter.Init(RouteFilterParams{}, field.dim(), reference.frames()), SeqSlamError::kOk);
    ASSERT_TRUE(Teach(filter, reference, field.dim()));
    int stop_row = -1;
    for (int r = 0; r < filter.rows(); ++r) {
      if (filter.row_last_frame(r) - filter.row_first_frame(r) >= 40)
        stop_row = r;
    }
    ASSERT_GE(stop_row, 0) << "the stop was not merged into one row";
    const std::vector<SeqSlamMatch> m = Repeat(filter, query, field.dim());
    int on_stop_row = 0, wrong = 0, middle_wrong = 0;
    for (int t = 10; t < query.frames(); ++t) {
      const SeqSlamMatch& match = m[static_cast<std::size_t>(t)];
      const double s = query.s_m[static_cast<std::size_t>(t)];
      if (!Within(reference, s, match.reference, 5)) {
        ++wrong;
        ADD_FAILURE() << "query " << q << " frame " << t << " at " << s << " m matched reference "
                      << match.reference << " (row " << match.row << ")";
      }
      if (match.row == stop_row) {
        ++on_stop_row;
        const int middle = (filter.row_first_frame(stop_row) + filter.row_last_frame(stop_row)) / 2;
        middle_wrong += Within(reference, s, middle, 5) ? 0 : 1;
      }
    }
    EXPECT_EQ(wrong, 0) << "query " << q;
    // The scenario shows the effect: pulling away, the middle of the stop would have been
    // wrong (passing through at 0.5 m/s, the best row is the stop's for only a frame or two).
    if (q == 1) {
      EXPECT_GE(middle_wrong, 2) << on_stop_row << " frames on the stop";
    }
  }
}

TEST(RouteFilter, ThreeTimesFasterThanTaughtIsFollowed) {
  Scenario sc;
  sc.reference = MakeRun(sc.field, SampleInTime({{60, 0.5}}, 10, 0.0), 0.02f, 21);
  sc.query = MakeRun(sc.field, SampleInTime({{9, 1.5}}, 10, 0.5), 0.02f, 22);
  RouteFilter filter;
  ASSERT_EQ(filter.Init(RouteFilterParams{}, sc.field.dim(), sc.reference.frames()),
            SeqSlamError::kOk);
  ASSERT_TRUE(Teach(filter, sc.reference, sc.field.dim()));
  const std::vector<SeqSlamMatch> m = Repeat(filter, sc.query, sc.field.dim());
  for (int t = 10; t < sc.query.frames(); ++t) {
    EXPECT_TRUE(Within(sc.reference, sc.query.s_m[static_cast<std::size_t>(t)],
                       m[static_cast<std::size_t>(t)].reference, 5))
        << "frame " << t;
  }
}

// An 80 s route at 1 m/s, and a query that drives 10 s from `from_m`, is carried to
// `to_m` (a kidnap) and drives on for 20 s: the carry is at query frame 100.
struct Kidnap {
  Scenario sc;
  std::vector<SeqSlamMatch> matches;
};
Kidnap RunKidnap(double from_m, double to_m, unsigned seed, const RouteFilterParams& p) {
  Kidnap k;
  Scenario& sc = k.sc;
  sc.reference = MakeRun(sc.field, SampleInTime({{80, 1.0}}, 10, 0.0), 0.02f, seed);
  std::vector<double> s = SampleInTime({{10, 1.0}}, 10, from_m);
  const std::vector<double> after = SampleInTime({{20, 1.0}}, 10, to_m);
  s.insert(s.end(), after.begin(), after.end());
  sc.query = MakeRun(sc.field, s, 0.02f, seed + 1);
  RouteFilter filter;
  EXPECT_EQ(filter.Init(p, sc.field.dim(), sc.reference.frames()), SeqSlamError::kOk);
  EXPECT_TRUE(Teach(filter, sc.reference, sc.field.dim()));
  k.matches = Repeat(filter, sc.query, sc.field.dim());
  return k;
}

TEST(RouteFilter, RelocalisesAfterAKidnap) {
  RouteFilterParams p;
  p.sequence_length = 10;
  const Kidnap k = RunKidnap(5.0, 50.0, 31, p);
  const std::vector<double>& s = k.sc.query.s_m;
  const std::vector<SeqSlamMatch>& m = k.matches;
  const Scenario& sc = k.sc;
  // Back on the truth within 2 ds frames of the kidnap (frame 100), and stays there.
  int back = -1;
  for (int t = 100; t < sc.query.frames() && back < 0; ++t) {
    if (Within(sc.reference, s[static_cast<std::size_t>(t)],
               m[static_cast<std::size_t>(t)].reference, 5))
      back = t;
  }
  ASSERT_GE(back, 100);
  EXPECT_LE(back - 100, 2 * p.sequence_length);
  for (int t = back; t < sc.query.frames(); ++t)
    EXPECT_TRUE(Within(sc.reference, s[static_cast<std::size_t>(t)],
                       m[static_cast<std::size_t>(t)].reference, 5))
        << "frame " << t;
}

// A best row that jumps against the motion (further back than the uniqueness window, or
// further forward than K rows and the window) ends the track it was on: the new track has
// not yet shown it keeps leading, and its confidence grows over 2 ds frames. Carried back
// 30 m, the filter's best row must jump; the frames right after are trusted less than the
// margin alone would say, and the track is fully trusted again 2 ds frames later.
TEST(RouteFilter, ABestRowThatJumpsBackStartsATrackWhoseConfidenceGrows) {
  RouteFilterParams p;
  p.sequence_length = 10;
  const std::vector<SeqSlamMatch> m = RunKidnap(40.0, 10.0, 33, p).matches;
  const int half = p.uniqueness_window / 2;
  int jumps = 0, last_jump = -1;
  for (std::size_t t = 1; t < m.size(); ++t) {
    const int move = m[t].row - m[t - 1].row;
    if (move < -half || move > p.max_advance + half) {
      ++jumps;
      last_jump = static_cast<int>(t);
      // The first frame of a track: at most 1 / (2 ds) of the margin's confidence.
      EXPECT_LE(m[t].confidence, 1.0f / (2.0f * static_cast<float>(p.sequence_length)))
          << "frame " << t;
    }
  }
  ASSERT_GE(jumps, 1);
  ASSERT_GE(last_jump, 100);  // the jump back comes after the carry
  // Frame k of the new track (k = 1 at the jump): at most k / (2 ds).
  for (int t = last_jump; t < last_jump + 2 * p.sequence_length; ++t)
    EXPECT_LE(
        m[static_cast<std::size_t>(t)].confidence,
        static_cast<float>(t - last_jump + 1) / (2.0f * static_cast<float>(p.sequence_length)))
        << "frame " << t;
  // Settled on the new track: as confident as before the carry.
  for (std::size_t t = static_cast<std::size_t>(last_jump + 4 * p.sequence_length); t < m.size();
       ++t)
    EXPECT_GT(m[t].confidence, 0.9f) << "frame " << t;
  for (std::size_t t = 2 * 10; t < 100; ++t)
    EXPECT_GT(m[t].confidence, 0.9f) << "frame " << t;
}

// The firmware's state machine (default [state], the filter's band of 0..K rows) on the
// filter's output, carried forward 45 m or back 30 m mid-run: how many frames until it
// is LOCALISED again at the right place, and LOCALISED is wrong only in the drop_frames
// frames right after the carry (the hysteresis: a LOCALISED robot needs drop_frames
// misses to drop). The bound is what docs/STATE_MACHINE.md states: the filter's own 2 ds
// to find the new place, the track's 2 ds of growing trust, and confirm_frames.
TEST(RouteFilter, TheStateMachineRelocalisesAfterAKidnapAndNeverLocalisesWrong) {
  for (const double carried_to_m : {50.0, 10.0}) {
    RouteFilterParams p;
    const Kidnap k = RunKidnap(carried_to_m > 40 ? 5.0 : 40.0, carried_to_m, 35, p);
    const Scenario& sc = k.sc;
    const std::vector<double>& s = sc.query.s_m;
    const std::vector<SeqSlamMatch>& m = k.matches;
    StateMachineParams sp;
    sp.vmin = 0;
    sp.vmax = p.max_advance;
    LocalisationStateMachine machine;
    ASSERT_EQ(machine.Init(sp), StateMachineError::kOk);
    int localised_again = -1, wrong_localised = 0;
    for (std::size_t t = 0; t < m.size(); ++t) {
      MatchObservation obs;
      obs.frame = t;
      obs.index = m[t].row;
      obs.uniqueness = m[t].uniqueness;
      obs.confidence = m[t].confidence;
      const LocalisationState state = machine.Update(obs);
      if (state != LocalisationState::kLocalised)
        continue;
      if (!Within(sc.reference, s[t], m[t].reference, 5)) {
        EXPECT_GE(t, 100u) << "carried to " << carried_to_m << " m: frame " << t;
        ++wrong_localised;
        continue;
      }
      if (t >= 100 && localised_again < 0)
        localised_again = static_cast<int>(t) - 100;
    }
    ASSERT_GE(localised_again, 0) << "carried to " << carried_to_m << " m";
    EXPECT_LE(localised_again, 4 * p.sequence_length + sp.confirm_frames)
        << "carried to " << carried_to_m << " m";
    // The wrong LOCALISED frames: the old place, until drop_frames misses in a row drop it.
    EXPECT_LE(wrong_localised, sp.drop_frames + 1) << "carried to " << carried_to_m << " m";
    std::printf(
        "carried to %.0f m: LOCALISED again %d frames after the carry, %d wrong LOCALISED\n",
        carried_to_m, localised_again, wrong_localised);
  }
}

TEST(RouteFilter, SingleImageIsNearestNeighbour) {
  const Scenario sc = StopsAndSpeeds();
  const int dim = sc.field.dim();
  RouteFilterParams p;
  p.sequence_length = 1;
  p.keyframe_noise_factor = 0;
  RouteFilter filter;
  ASSERT_EQ(filter.Init(p, dim, sc.reference.frames()), SeqSlamError::kOk);
  ASSERT_TRUE(Teach(filter, sc.reference, dim));
  std::vector<float> column(static_cast<std::size_t>(sc.reference.frames()));
  for (int t = 0; t < sc.query.frames(); ++t) {
    SeqSlamMatch m;
    ASSERT_EQ(filter.Step(sc.query.Frame(t, dim), &m), SeqSlamError::kOk);
    DifferenceColumn(sc.reference.descriptors, dim, sc.query.Frame(t, dim), column);
    const int nearest =
        static_cast<int>(std::min_element(column.begin(), column.end()) - column.begin());
    EXPECT_EQ(m.reference, nearest) << "frame " << t;
  }
}

// The failure the filter replaces (docs/SEQSLAM.md): a route sampled densely in space, so
// the basin of alike frames around each place is ~20 frames wide. OpenSeqSLAM's
// enhancement against +-R/2 = 5 neighbouring rows turns the basin's floor into a plateau
// and puts the enhanced minimum near its edge, about R/2 frames from the truth; the
// filter's whole-route z-score keeps the minimum where the descriptor puts it.
TEST(RouteFilter, NoBasinEdgeShiftWhereFixedWindowEnhancementHasOne) {
  AppearanceField field(24, 5, 6.0, 20.0);
  const TimedRun reference = MakeRun(field, SampleInTime({{40, 1.0}}, 20, 0.0), 0.0f, 41);
  // The query: the same places half a frame along, with a little noise.
  const TimedRun query = MakeRun(field, SampleInTime({{30, 1.0}}, 20, 5.025), 0.002f, 42);
  const int dim = field.dim(), n = reference.frames();
  std::vector<float> column(static_cast<std::size_t>(n)), enhanced(column.size());
  double enhanced_error = 0;
  for (int t = 0; t < query.frames(); ++t) {
    DifferenceColumn(reference.descriptors, dim, query.Frame(t, dim), column);
    EnhanceColumn(column, 10, enhanced);
    const int truth = 100 + t;  // 5.025 m at 0.05 m per frame, rounded down
    const int e =
        static_cast<int>(std::min_element(enhanced.begin(), enhanced.end()) - enhanced.begin());
    enhanced_error += std::abs(e - truth);
  }
  enhanced_error /= query.frames();
  EXPECT_GT(enhanced_error, 3.0) << "fixed-window enhancement no longer shows the shift";

  RouteFilterParams p;
  p.sequence_length = 1;
  RouteFilter filter;
  ASSERT_EQ(filter.Init(p, dim, n), SeqSlamError::kOk);
  ASSERT_TRUE(Teach(filter, reference, dim));
  double filter_error = 0;
  for (int t = 0; t < query.frames(); ++t) {
    SeqSlamMatch m;
    ASSERT_EQ(filter.Step(query.Frame(t, dim), &m), SeqSlamError::kOk);
    filter_error += std::abs(m.reference - (100 + t));
  }
  filter_error /= query.frames();
  EXPECT_LE(filter_error, 1.0);
}

TEST(RouteFilter, ConfidenceFallsOnAnUntaughtRoute) {
  Scenario sc;
  sc.reference = MakeRun(sc.field, SampleInTime({{40, 1.0}}, 10, 0.0), 0.02f, 51);
  sc.query = MakeRun(sc.field, SampleInTime({{20, 1.0}}, 10, 5.0), 0.02f, 52);
  const AppearanceField elsewhere(24, 99);
  const TimedRun untaught = MakeRun(elsewhere, SampleInTime({{20, 1.0}}, 10, 0.0), 0.02f, 53);
  RouteFilter filter;
  ASSERT_EQ(filter.Init(RouteFilterParams{}, sc.field.dim(), sc.reference.frames()),
            SeqSlamError::kOk);
  ASSERT_TRUE(Teach(filter, sc.reference, sc.field.dim()));
  const std::vector<SeqSlamMatch> on = Repeat(filter, sc.query, sc.field.dim());
  filter.ResetQueries();
  const std::vector<SeqSlamMatch> off = Repeat(filter, untaught, sc.field.dim());
  // Every on-route frame after warm-up (2 ds frames: the confidence of a new track grows
  // over them) is more confident than the most confident off-route frame.
  float off_max = 0;
  for (const SeqSlamMatch& m : off)
    off_max = std::max(off_max, m.confidence);
  for (std::size_t t = 2 * 10; t < on.size(); ++t)
    EXPECT_GT(on[t].confidence, off_max) << "frame " << t;
}

// ---- The search window (route_filter.h, 6.) ------------------------------------------

// A long route for the window: 120 s at 1 m/s, 1,200 rows (nothing merges: no stops), and
// a repeat that drives 60 s of it at 1.5x with a 3 s stop.
Scenario LongRoute() {
  Scenario sc;
  sc.reference = MakeRun(sc.field, SampleInTime({{120, 1.0}}, 10, 0.0), 0.02f, 61);
  sc.query = MakeRun(sc.field, SampleInTime({{20, 1.5}, {3, 0}, {37, 1.5}}, 10, 10.0), 0.02f, 62);
  return sc;
}

struct WindowRun {
  std::vector<SeqSlamMatch> matches;
  std::vector<std::vector<bool>> compared;  // [frame][row]: RowCompared after the frame
  std::vector<int> rows_compared;
  int rows = 0;
};

WindowRun RunWindowed(const Scenario& sc, const RouteFilterParams& p,
                      ReferenceStorage storage = ReferenceStorage::kFloat32) {
  WindowRun w;
  const int dim = sc.field.dim();
  RouteFilter filter;
  EXPECT_EQ(filter.Init(p, dim, sc.reference.frames(), storage), SeqSlamError::kOk);
  EXPECT_TRUE(Teach(filter, sc.reference, dim));
  w.rows = filter.rows();
  for (int t = 0; t < sc.query.frames(); ++t) {
    SeqSlamMatch m;
    EXPECT_EQ(filter.Step(sc.query.Frame(t, dim), &m), SeqSlamError::kOk);
    w.matches.push_back(m);
    std::vector<bool> row(static_cast<std::size_t>(w.rows));
    for (int r = 0; r < w.rows; ++r)
      row[static_cast<std::size_t>(r)] = filter.RowCompared(r);
    w.compared.push_back(std::move(row));
    w.rows_compared.push_back(filter.rows_compared());
  }
  return w;
}

::testing::AssertionResult SameOutput(const std::vector<SeqSlamMatch>& a,
                                      const std::vector<SeqSlamMatch>& b) {
  if (a.size() != b.size())
    return ::testing::AssertionFailure() << a.size() << " against " << b.size() << " frames";
  for (std::size_t t = 0; t < a.size(); ++t) {
    if (a[t].row != b[t].row || a[t].reference != b[t].reference ||
        std::bit_cast<std::uint32_t>(a[t].confidence) !=
            std::bit_cast<std::uint32_t>(b[t].confidence) ||
        std::bit_cast<std::uint32_t>(a[t].score) != std::bit_cast<std::uint32_t>(b[t].score) ||
        std::bit_cast<std::uint32_t>(a[t].uniqueness) !=
            std::bit_cast<std::uint32_t>(b[t].uniqueness))
      return ::testing::AssertionFailure()
             << "frame " << t << ": row " << a[t].row << " / " << b[t].row << ", confidence "
             << a[t].confidence << " / " << b[t].confidence;
  }
  return ::testing::AssertionSuccess();
}

// With refresh_frames 1 every row is compared on every frame (the window's and the slice's
// parts assembled into the whole column), and with a window as wide as the route too: the
// output is the full scan's to the bit. With refresh_frames 5 the rows outside the window
// are stale and the output differs (so the comparison can fail).
TEST(RouteFilter, SearchWindowThatComparesEveryRowEqualsTheFullScanToTheBit) {
  const Scenario sc = LongRoute();
  for (const ReferenceStorage storage : {ReferenceStorage::kFloat32, ReferenceStorage::kCodes16}) {
    const RouteFilterParams off;
    const WindowRun full = RunWindowed(sc, off, storage);
    ASSERT_GT(full.rows, 1000);
    RouteFilterParams every_frame = off;
    every_frame.search_window = 16;
    every_frame.refresh_frames = 1;
    const WindowRun one = RunWindowed(sc, every_frame, storage);
    EXPECT_TRUE(SameOutput(one.matches, full.matches));
    for (std::size_t t = 0; t < one.rows_compared.size(); ++t)
      ASSERT_EQ(one.rows_compared[t], one.rows) << "frame " << t;
    RouteFilterParams covering = off;
    covering.search_window = full.rows;
    covering.refresh_frames = 7;
    EXPECT_TRUE(SameOutput(RunWindowed(sc, covering, storage).matches, full.matches));
    RouteFilterParams stale = every_frame;
    stale.refresh_frames = 5;
    EXPECT_FALSE(SameOutput(RunWindowed(sc, stale, storage).matches, full.matches));
  }
}

// Which rows a frame compares: every row on the first frame after a reset; afterwards the
// rows within +-search_window of the last best row, and each other row exactly once in
// every refresh_frames consecutive frames. The output is then a second implementation's
// (the naive filter of docs/SEQSLAM.md, in doubles) fed the same schedule: the stale rows
// keep their last difference and everything else runs over the whole column.
TEST(RouteFilter, SearchWindowComparesEachStaleRowOnceEveryRefreshFrames) {
  const Scenario sc = LongRoute();
  const int dim = sc.field.dim();
  RouteFilterParams p;
  p.search_window = 24;
  p.refresh_frames = 7;  // 1,200 rows are not a multiple of 7: slices of 171 and 172 rows
  const WindowRun w = RunWindowed(sc, p, ReferenceStorage::kFloat32);
  const int n = w.rows, frames = static_cast<int>(w.matches.size());
  const auto at = [](int i) { return static_cast<std::size_t>(i); };
  for (int r = 0; r < n; ++r)
    ASSERT_TRUE(w.compared[0][at(r)]) << "first frame, row " << r;
  ASSERT_EQ(w.rows_compared[0], n);
  int checked_rows = 0;
  for (int t = 1; t < frames; ++t) {
    const int last_best = w.matches[at(t - 1)].row;
    int count = 0;
    for (int r = 0; r < n; ++r) {
      const bool in_window = std::abs(r - last_best) <= p.search_window;
      if (in_window) {
        EXPECT_TRUE(w.compared[at(t)][at(r)]) << "frame " << t << ", row " << r;
      }
      count += w.compared[at(t)][at(r)] ? 1 : 0;
    }
    EXPECT_EQ(w.rows_compared[at(t)], count) << "frame " << t;
    EXPECT_LE(count, 2 * p.search_window + 1 + (n + p.refresh_frames - 1) / p.refresh_frames);
  }
  // Rows no window came near: compared exactly once in every run of refresh_frames frames
  // (after the first, which compares all).
  for (int r = 0; r < n; ++r) {
    bool ever_in_window = false;
    for (int t = 1; t < frames; ++t)
      ever_in_window |= std::abs(r - w.matches[at(t - 1)].row) <= p.search_window;
    if (ever_in_window)
      continue;
    ++checked_rows;
    for (int t = 1; t + p.refresh_frames <= frames; ++t) {
      int times = 0;
      for (int u = t; u < t + p.refresh_frames; ++u)
        times += w.compared[at(u)][at(r)] ? 1 : 0;
      ASSERT_EQ(times, 1) << "row " << r << ", frames " << t << ".." << t + p.refresh_frames - 1;
    }
  }
  EXPECT_GT(checked_rows, n / 5);  // the repeat's windows cover 10-96 m of the 120

  const NaiveResult naive = NaiveFilter(sc.reference, sc.query, dim, p, &w.compared);
  ASSERT_EQ(static_cast<int>(naive.first.size()), n);
  int compared = 0;
  for (std::size_t t = 0; t < w.matches.size(); ++t) {
    if (naive.gap[t] < 1e-4)
      continue;  // float and double may order near-ties either way
    ++compared;
    EXPECT_EQ(w.matches[t].row, naive.row[t]) << "frame " << t;
    EXPECT_NEAR(w.matches[t].confidence, naive.confidence[t], 1e-4) << "frame " << t;
  }
  EXPECT_GT(compared, frames * 9 / 10);
  // The same filter after a reset compares every row again on its first frame.
  RouteFilter filter;
  ASSERT_EQ(filter.Init(p, dim, sc.reference.frames()), SeqSlamError::kOk);
  ASSERT_TRUE(Teach(filter, sc.reference, dim));
  SeqSlamMatch m;
  for (int t = 0; t < 3; ++t)
    ASSERT_EQ(filter.Step(sc.query.Frame(t, dim), &m), SeqSlamError::kOk);
  ASSERT_LT(filter.rows_compared(), n);
  filter.ResetQueries();
  ASSERT_EQ(filter.Step(sc.query.Frame(0, dim), &m), SeqSlamError::kOk);
  EXPECT_EQ(filter.rows_compared(), n);
}

// After a kidnap to a place outside the window, the new place is compared only in its
// slice: the filter is back on the truth at most refresh_frames frames later than the full
// scan, and stays there.
TEST(RouteFilter, SearchWindowRelocalisesAfterAKidnapWithinRefreshFramesMore) {
  const auto back_on_truth = [](const Kidnap& k) {
    const std::vector<double>& s = k.sc.query.s_m;
    for (int t = 100; t < k.sc.query.frames(); ++t) {
      if (Within(k.sc.reference, s[static_cast<std::size_t>(t)],
                 k.matches[static_cast<std::size_t>(t)].reference, 5))
        return t - 100;
    }
    return -1;
  };
  for (const double to_m : {35.0, 50.0}) {
    RouteFilterParams p;
    const Kidnap full = RunKidnap(5.0, to_m, 31, p);
    const int full_delay = back_on_truth(full);
    ASSERT_GE(full_delay, 0);
    p.search_window = 20;  // 20-35 m (200-350 rows) from the last best row: far outside
    for (const int f : {5, 10, 20}) {
      p.refresh_frames = f;
      const Kidnap k = RunKidnap(5.0, to_m, 31, p);
      const int delay = back_on_truth(k);
      ASSERT_GE(delay, 0) << "F " << f << ", to " << to_m << " m";
      EXPECT_LE(delay, full_delay + f) << "F " << f << ", to " << to_m << " m";
      EXPECT_LE(delay, p.sequence_length + f) << "F " << f << ", to " << to_m << " m";
      for (int t = 100 + delay; t < k.sc.query.frames(); ++t)
        EXPECT_TRUE(Within(k.sc.reference, k.sc.query.s_m[static_cast<std::size_t>(t)],
                           k.matches[static_cast<std::size_t>(t)].reference, 5))
            << "F " << f << ", to " << to_m << " m, frame " << t;
      std::printf("kidnap to %.0f m: on the truth %d frames after the carry (full scan %d), F %d\n",
                  to_m, delay, full_delay, f);
    }
  }
}

TEST(RouteFilter, StepAllocatesNothing) {
  const Scenario sc = StopsAndSpeeds();
  RouteFilterParams windowed;  // the search window, its slices and its reset
  windowed.search_window = 8;
  windowed.refresh_frames = 4;
  for (const RouteFilterParams& p : {RouteFilterParams{}, windowed}) {
    RouteFilter filter;
    ASSERT_EQ(filter.Init(p, sc.field.dim(), sc.reference.frames(), ReferenceStorage::kBFloat16),
              SeqSlamError::kOk);
    ASSERT_TRUE(AllocationCounterActive());
    AllocationScope scope;
    for (int i = 0; i < sc.reference.frames(); ++i)
      ASSERT_EQ(filter.AddReference(sc.reference.Frame(i, sc.field.dim())), SeqSlamError::kOk);
    ASSERT_EQ(filter.FinishRoute(), SeqSlamError::kOk);
    SeqSlamMatch m;
    for (int t = 0; t < sc.query.frames(); ++t) {
      ASSERT_EQ(filter.Step(sc.query.Frame(t, sc.field.dim()), &m), SeqSlamError::kOk);
      if (t == sc.query.frames() / 2)
        filter.ResetQueries();
    }
    EXPECT_EQ(scope.allocations(), 0u) << "search_window " << p.search_window;
    if (p.search_window > 0) {
      EXPECT_LT(filter.rows_compared(), filter.rows());  // the window was used
    }
  }
}

TEST(RouteFilter, RefusesBadParametersAndCallOrder) {
  RouteFilterParams p;
  p.max_advance = 0;
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadMaxAdvance);
  p = {};
  p.sequence_length = 0;
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadSequenceLength);
  p = {};
  p.keyframe_noise_factor = -1;
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadKeyframeFactor);
  p.keyframe_noise_factor = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadKeyframeFactor);
  p = {};
  p.search_window = -1;
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadSearchWindow);
  p.search_window = kMaxSearchWindow + 1;
  p.refresh_frames = 10;
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadSearchWindow);
  p.search_window = kMaxSearchWindow;
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kOk);
  for (const int f : {0, kMaxRefreshFrames + 1}) {
    p.refresh_frames = f;
    EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadRefreshFrames) << f;
  }
  p.refresh_frames = kMaxRefreshFrames;
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kOk);
  p.search_window = 0;  // no window: refresh_frames would be ignored, so it is refused
  EXPECT_EQ(ValidateRouteFilterParams(p), SeqSlamError::kBadRefreshFrames);
  EXPECT_NE(
      std::string(SeqSlamErrorMessage(SeqSlamError::kBadRefreshFrames)).find("refresh_frames"),
      std::string::npos);
  EXPECT_NE(std::string(SeqSlamErrorMessage(SeqSlamError::kBadSearchWindow)).find("search_window"),
            std::string::npos);
  {
    RouteFilter refused;
    EXPECT_EQ(refused.Init(p, 4, 2), SeqSlamError::kBadRefreshFrames);
  }

  RouteFilter filter;
  SeqSlamMatch m;
  const std::vector<float> d(4, 1.0f);
  EXPECT_EQ(filter.Step(d, &m), SeqSlamError::kNotInitialised);
  ASSERT_EQ(filter.Init(RouteFilterParams{}, 4, 2), SeqSlamError::kOk);
  ASSERT_EQ(filter.AddReference(d), SeqSlamError::kOk);
  EXPECT_EQ(filter.Step(d, &m), SeqSlamError::kRouteNotFinished);
  ASSERT_EQ(filter.FinishRoute(), SeqSlamError::kOk);
  EXPECT_EQ(filter.AddReference(d), SeqSlamError::kRouteFinished);
  ASSERT_EQ(filter.Step(d, &m), SeqSlamError::kOk);
  EXPECT_TRUE(m.valid);
  EXPECT_EQ(m.reference, 0);
  EXPECT_EQ(m.confidence, 0.0f);  // one row: nothing to be distinctive against
  filter.ClearReferences();
  ASSERT_EQ(filter.FinishRoute(), SeqSlamError::kOk);
  EXPECT_EQ(filter.Step(d, &m), SeqSlamError::kEmptyDatabase);
  EXPECT_EQ(filter.Step(std::vector<float>(3), &m), SeqSlamError::kSizeMismatch);
}

}  // namespace
}  // namespace skyloc::dsp
