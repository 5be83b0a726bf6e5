#include "skyloc/dsp/surf1d.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/strip_alignment.h"
#include "skyloc/platform/alloc_counter.h"
#include "support/angles.h"

namespace skyloc::dsp {
namespace {

// A rough integer-valued strip (a smoothed random walk), so that integral sums are exact
// and shifted copies give bit-identical responses.
std::vector<float> IntegerStrip(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> step(-6, 6);
  std::vector<float> s(static_cast<std::size_t>(n));
  int v = 120;
  for (auto& x : s) {
    v = std::clamp(v + step(rng), 10, 245);
    x = static_cast<float>(v);
  }
  return s;
}

std::vector<float> Shifted(const std::vector<float>& s, int k) {
  const int n = static_cast<int>(s.size());
  std::vector<float> out(s.size());
  for (int j = 0; j < n; ++j)
    out[static_cast<std::size_t>((j + k) % n)] = s[static_cast<std::size_t>(j)];
  return out;
}

std::vector<Surf1dFeature> DetectAll(Surf1d& surf, const std::vector<float>& strip) {
  std::vector<Surf1dFeature> f(512);
  int count = 0;
  EXPECT_EQ(surf.Detect(strip, f, &count), Surf1dError::kOk);
  f.resize(static_cast<std::size_t>(count));
  return f;
}

TEST(Surf1dTest, LayersAreTheDistinctSurfLobeWidths) {
  Surf1d surf;
  ASSERT_EQ(surf.Init(360, Surf1dOptions{}), Surf1dError::kOk);
  const std::vector<int> expected = {3, 5, 7, 9, 13, 17, 25, 33, 49};
  EXPECT_EQ(std::vector<int>(surf.lobes().begin(), surf.lobes().end()), expected);
  EXPECT_EQ(Surf1dMaxLobe(Surf1dOptions{}), 49);
}

// Second implementation: the three lobes summed sample by sample with wrap-around.
TEST(Surf1dTest, BoxResponseEqualsDirectLobeSums) {
  const int n = 257;
  const std::vector<float> s = IntegerStrip(n, 3);
  Surf1d surf;
  ASSERT_EQ(surf.Init(n, Surf1dOptions{}), Surf1dError::kOk);
  DetectAll(surf, s);
  const auto at = [&](int i) {
    return static_cast<double>(s[static_cast<std::size_t>(((i % n) + n) % n)]);
  };
  for (int layer = 0; layer < static_cast<int>(surf.lobes().size()); ++layer) {
    const int l = surf.lobes()[static_cast<std::size_t>(layer)];
    for (int x = 0; x < n; ++x) {
      double d = 0.0;
      for (int k = -(l - 1) / 2; k <= (l - 1) / 2; ++k)
        d += at(x - l + k) + at(x + l + k) - 2.0 * at(x + k);
      ASSERT_NEAR(surf.Response(layer, x), d / l, 1e-4 * (1.0 + std::abs(d / l)))
          << "l=" << l << " x=" << x;
    }
  }
}

// On a cosine the box filter has a closed form (box gain times second-difference gain),
// and at low frequency it matches the Gaussian second derivative of sigma^2 = l^2/4 - 1/12.
TEST(Surf1dTest, BoxResponseOnCosineMatchesClosedFormAndGaussianDerivative) {
  const int n = 512;
  const double amplitude = 50.0;
  for (const int cycles : {1, 2, 3, 7}) {
    const double w = 2.0 * kPi * cycles / n;
    std::vector<float> s(n);
    for (int x = 0; x < n; ++x)
      s[static_cast<std::size_t>(x)] = static_cast<float>(128.0 + amplitude * std::cos(w * x));
    Surf1d surf;
    ASSERT_EQ(surf.Init(n, Surf1dOptions{}), Surf1dError::kOk);
    DetectAll(surf, s);
    for (int layer = 0; layer < static_cast<int>(surf.lobes().size()); ++layer) {
      const double l = surf.lobes()[static_cast<std::size_t>(layer)];
      const double gain = -4.0 * std::pow(std::sin(w * l / 2), 3) / std::sin(w / 2);
      const double sigma2 = l * l / 4 - 1.0 / 12;
      const double gaussian = -w * w * std::exp(-w * w * sigma2 / 2);
      for (int x = 0; x < n; x += 17) {
        const double d = static_cast<double>(surf.Response(layer, x)) * l;
        EXPECT_NEAR(d, gain * amplitude * std::cos(w * x), 2e-3 * amplitude);
        if (w * std::sqrt(sigma2) <= 0.6) {
          // Fourth-order agreement: within 0.5 % of the peak second derivative.
          EXPECT_NEAR(d / (l * l * l), gaussian * amplitude * std::cos(w * x),
                      5e-3 * w * w * amplitude);
        }
      }
    }
  }
}

// The continuous response of the box filter to a Gaussian blob A exp(-x^2 / 2 sb^2) at its
// centre, from the error function: lobes [-3l/2, -l/2], [-l/2, l/2], [l/2, 3l/2].
double AnalyticBlobResponse(double l, double sb) {
  const auto e = [&](double a) { return std::erf(a / (sb * std::sqrt(2.0))); };
  return sb * std::sqrt(kPi / 2) * (2 * e(1.5 * l) - 6 * e(0.5 * l)) / l;
}

TEST(Surf1dTest, GaussianBlobIsFoundAtItsAnalyticScaleAndPosition) {
  const int n = 512;
  Surf1dOptions options;
  options.suppress_across_scale = true;
  options.threshold = 1.0f;
  for (const double sb : {2.0, 4.0, 5.0, 10.0}) {
    for (const double sign : {1.0, -1.0}) {
      const int centre = 300;
      std::vector<float> s(n);
      for (int x = 0; x < n; ++x) {
        const double u = x - centre;
        s[static_cast<std::size_t>(x)] =
            static_cast<float>(100.0 + sign * 80.0 * std::exp(-u * u / (2 * sb * sb)));
      }
      Surf1d surf;
      ASSERT_EQ(surf.Init(n, options), Surf1dError::kOk);
      const std::vector<Surf1dFeature> f = DetectAll(surf, s);
      int predicted = 0;
      double best = 0.0;
      for (int layer = 0; layer < static_cast<int>(surf.lobes().size()); ++layer) {
        const double r =
            std::abs(AnalyticBlobResponse(surf.lobes()[static_cast<std::size_t>(layer)], sb));
        if (r > best) {
          best = r;
          predicted = layer;
        }
      }
      const auto hit = std::find_if(f.begin(), f.end(),
                                    [&](const Surf1dFeature& g) { return g.position == centre; });
      ASSERT_NE(hit, f.end()) << "sb=" << sb;
      EXPECT_EQ(hit->layer, predicted) << "sb=" << sb;
      EXPECT_EQ(hit->laplacian_sign, sign > 0 ? -1 : 1);
      EXPECT_NEAR(std::abs(hit->response), 80.0 * best, 0.03 * 80.0 * best);
      // Exactly one feature at the blob's centre across scales.
      EXPECT_EQ(
          std::count_if(f.begin(), f.end(),
                        [&](const Surf1dFeature& g) { return std::abs(g.position - centre) <= 1; }),
          1);
    }
  }
}

TEST(Surf1dTest, ShiftedStripGivesShiftedFeaturesWithIdenticalDescriptors) {
  const int n = 360;
  const std::vector<float> s = IntegerStrip(n, 11);
  Surf1d surf;
  ASSERT_EQ(surf.Init(n, Surf1dOptions{}), Surf1dError::kOk);
  const std::vector<Surf1dFeature> base = DetectAll(surf, s);
  ASSERT_GE(base.size(), 20u);
  ASSERT_EQ(surf.dropped(), 0);
  LandmarkMatcher matcher;
  ASSERT_EQ(matcher.Init(512, LandmarkMatchOptions{}), Surf1dError::kOk);
  for (const int k : {1, 37, 180, 300, 359}) {
    const std::vector<Surf1dFeature> moved = DetectAll(surf, Shifted(s, k));
    ASSERT_EQ(moved.size(), base.size()) << "k=" << k;
    for (const Surf1dFeature& a : base) {
      const auto b = std::find_if(moved.begin(), moved.end(), [&](const Surf1dFeature& g) {
        return g.position == (a.position + k) % n && g.layer == a.layer;
      });
      ASSERT_NE(b, moved.end()) << "k=" << k << " position " << a.position;
      EXPECT_EQ(b->response, a.response);
      EXPECT_EQ(b->descriptor, a.descriptor);
    }
    LandmarkMatch m;
    ASSERT_EQ(matcher.Match(base, moved, n, &m), Surf1dError::kOk);
    ASSERT_TRUE(m.model_found);
    double expected = k * 360.0 / n;
    if (expected >= 180.0)
      expected -= 360.0;
    EXPECT_NEAR(m.heading_offset_deg, expected, 360.0 / n) << "k=" << k;
    EXPECT_NEAR(m.scale, 1.0, 1e-9);
    EXPECT_GE(m.inliers, m.matches * 9 / 10);
  }
}

// --- Synthetic places: a skyline (elevation of the sky's lower edge, degrees, per
// azimuth) above textured ground. Pixels above the skyline are sky (220), below it ground
// whose brightness varies with azimuth (buildings, trees).
struct Place {
  std::vector<double> harmonics;  // a, b pairs
  std::vector<double> texture;
  double Skyline(double phi) const {
    double h = 9.0;
    for (std::size_t k = 0; k < harmonics.size() / 2; ++k)
      h += harmonics[2 * k] * std::cos(static_cast<double>(k + 1) * phi) +
           harmonics[2 * k + 1] * std::sin(static_cast<double>(k + 1) * phi);
    return h;
  }
  double Ground(double phi) const {
    double g = 70.0;
    for (std::size_t k = 0; k < texture.size() / 2; ++k)
      g += texture[2 * k] * std::cos(static_cast<double>(k + 3) * phi) +
           texture[2 * k + 1] * std::sin(static_cast<double>(k + 3) * phi);
    return g;
  }
};

Place RandomPlace(unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Place p;
  for (int k = 0; k < 24; ++k) {
    const double a = 7.0 / (1.0 + 0.25 * (k / 2));
    p.harmonics.push_back(a * normal(rng) / 2.0);
  }
  for (int k = 0; k < 20; ++k)
    p.texture.push_back(12.0 * normal(rng) / (1.0 + 0.2 * (k / 2)));
  return p;
}

// The place's value seen at body azimuth phi and elevation (degrees) when the scene is
// turned by yaw (radians) towards increasing azimuth.
double SceneValue(const Place& p, double phi, double elevation_deg, double yaw) {
  const double world = phi - yaw;
  return elevation_deg > p.Skyline(world) ? 220.0 : p.Ground(world);
}

std::vector<std::uint8_t> RenderFisheye(const Lens& lens, const Place& p, double yaw) {
  const int w = lens.params().width, h = lens.params().height;
  std::vector<std::uint8_t> grey(static_cast<std::size_t>(w * h), 0);
  Eigen::Vector3d ray;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!lens.PixelToRay(x, y, &ray))
        continue;
      const double elevation = std::asin(std::clamp(ray.z(), -1.0, 1.0)) * 180.0 / kPi;
      const double v = SceneValue(p, std::atan2(ray.y(), ray.x()), elevation, yaw);
      grey[static_cast<std::size_t>(y * w + x)] =
          static_cast<std::uint8_t>(std::clamp(v, 0.0, 255.0));
    }
  }
  return grey;
}

// One place rendered through a 640x480 equidistant 185-degree fisheye at any yaw, and the
// horizon strip of each rendering: what both heading methods are tested on.
class FisheyeStrips : public ::testing::Test {
 protected:
  void SetUp() override {
    LensParams params;
    params.model = LensModel::kEquidistant;
    params.width = 640;
    params.height = 480;
    params.fov_deg = 185.0;
    ASSERT_EQ(lens_.Init(params), LensError::kOk);
    ASSERT_EQ(strip_.Init(lens_, HorizonStripOptions{}), HorizonStripError::kOk);
  }
  std::vector<float> StripAt(double yaw_deg) {
    const std::vector<std::uint8_t> grey = RenderFisheye(lens_, place_, yaw_deg * kPi / 180.0);
    std::vector<float> values(static_cast<std::size_t>(strip_.n_azimuth()));
    EXPECT_EQ(strip_.Extract({grey.data(), 640, 480, 640, PixelFormat::kGrey8}, values),
              HorizonStripError::kOk);
    return values;
  }
  Lens lens_;
  HorizonStrip strip_;
  const Place place_ = RandomPlace(5);
};

TEST_F(FisheyeStrips, SurfRecoversTheYawOfTheScene) {
  const HorizonStrip& strip = strip_;
  Surf1d surf;
  ASSERT_EQ(surf.Init(strip.n_azimuth(), Surf1dOptions{}), Surf1dError::kOk);
  LandmarkMatcher matcher;
  ASSERT_EQ(matcher.Init(512, LandmarkMatchOptions{}), Surf1dError::kOk);

  const auto features_for = [&](double yaw_deg) { return DetectAll(surf, StripAt(yaw_deg)); };
  const std::vector<Surf1dFeature> stored = features_for(0.0);
  ASSERT_GE(stored.size(), 15u);
  for (const double yaw : {23.5, -71.2, 178.4, -163.0}) {
    const std::vector<Surf1dFeature> test = features_for(yaw);
    LandmarkMatch m;
    ASSERT_EQ(matcher.Match(stored, test, strip.n_azimuth(), &m), Surf1dError::kOk);
    ASSERT_TRUE(m.model_found) << "yaw " << yaw;
    double error = m.heading_offset_deg - yaw;
    error -= 360.0 * std::round(error / 360.0);
    EXPECT_LE(std::abs(error), 2.0) << "yaw " << yaw << " recovered " << m.heading_offset_deg;
    EXPECT_GE(m.inliers, 8) << "yaw " << yaw;
    // The pairs a tool draws are the ones RANSAC counted.
    ASSERT_EQ(matcher.last_pair_count(), m.matches);
    int flagged = 0;
    for (int i = 0; i < matcher.last_pair_count(); ++i)
      flagged += matcher.last_pair(i).inlier ? 1 : 0;
    EXPECT_EQ(flagged, m.inliers) << "yaw " << yaw;
    std::printf("yaw %+7.1f deg: recovered %+7.2f deg, %zu/%zu features, %d matches, %d inliers\n",
                yaw, m.heading_offset_deg, stored.size(), test.size(), m.matches, m.inliers);
  }
}

// The second heading method on the same rendered fisheye frames: circular correlation of
// the whole strips (strip_alignment.h) agrees with the true yaw as 1D SURF does.
// The frame path's correlator by FFT gives the definition's peak to the bit on them.
TEST_F(FisheyeStrips, StripCorrelationRecoversTheSameYaw) {
  const std::vector<float> stored = StripAt(0.0);
  StripCorrelator correlator;
  ASSERT_TRUE(correlator.Init(static_cast<int>(stored.size())));
  ASSERT_EQ(correlator.SetStored(stored), StripAlignmentError::kOk);
  for (const double yaw : {23.5, -71.2, 178.4, -163.0}) {
    const std::vector<float> test = StripAt(yaw);
    StripAlignment a, by_fft;
    ASSERT_EQ(AlignStrips(stored, test, &a), StripAlignmentError::kOk);
    double error = a.heading_offset_deg - yaw;
    error -= 360.0 * std::round(error / 360.0);
    EXPECT_LE(std::abs(error), 1.0) << "yaw " << yaw << " recovered " << a.heading_offset_deg;
    EXPECT_GT(a.correlation, 0.9f);
    ASSERT_EQ(correlator.Align(test, &by_fft), StripAlignmentError::kOk);
    EXPECT_EQ(by_fft.shift_columns, a.shift_columns) << "yaw " << yaw;
    EXPECT_EQ(by_fft.heading_offset_deg, a.heading_offset_deg) << "yaw " << yaw;
    EXPECT_EQ(by_fft.correlation, a.correlation) << "yaw " << yaw;
  }
}

// The band-mean strip of a place, straight from the scene model (the same average the
// horizon strip takes, without rendering an image), with a view change: turned by yaw,
// contrast and brightness changed, the skyline raised or lowered a little on one side (a
// small translation), and pixel noise.
std::vector<float> PlaceStrip(const Place& p, int n, double yaw, double gain, double offset,
                              double tilt, std::mt19937* rng) {
  std::normal_distribution<double> noise(0.0, 1.5);
  std::vector<float> s(static_cast<std::size_t>(n));
  Place seen = p;
  for (int j = 0; j < n; ++j) {
    const double phi = 2.0 * kPi * j / n;
    double sum = 0.0;
    for (int r = 0; r < 16; ++r) {
      const double elevation = (r + 0.5) * 20.0 / 16 - tilt * std::cos(phi - yaw);
      sum += SceneValue(seen, phi, elevation, yaw);
    }
    s[static_cast<std::size_t>(j)] = static_cast<float>(gain * sum / 16 + offset + noise(*rng));
  }
  return s;
}

// Area under the ROC curve (Mann-Whitney): the chance that a matched pair outscores an
// unmatched one, ties counting half.
double Auc(const std::vector<double>& positives, const std::vector<double>& negatives) {
  double wins = 0.0;
  for (const double a : positives)
    for (const double b : negatives)
      wins += a > b ? 1.0 : (a == b ? 0.5 : 0.0);
  return wins / (static_cast<double>(positives.size()) * static_cast<double>(negatives.size()));
}

TEST(Surf1dTest, MatchedPlacesOutscoreUnrelatedOnes) {
  const int n = 360, places = 30;
  Surf1d surf;
  ASSERT_EQ(surf.Init(n, Surf1dOptions{}), Surf1dError::kOk);
  LandmarkMatcher matcher;
  ASSERT_EQ(matcher.Init(512, LandmarkMatchOptions{}), Surf1dError::kOk);
  std::mt19937 rng(2012);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::vector<std::vector<Surf1dFeature>> stored, test;
  std::vector<double> yaws;
  for (int p = 0; p < places; ++p) {
    const Place place = RandomPlace(100u + static_cast<unsigned>(p));
    stored.push_back(DetectAll(surf, PlaceStrip(place, n, 0.0, 1.0, 0.0, 0.0, &rng)));
    const double yaw = (uniform(rng) * 2.0 - 1.0) * kPi;
    yaws.push_back(yaw);
    // One draw per statement: a call's arguments are evaluated in an unspecified order
    // (right to left by GCC on x86-64, left to right on ARM).
    const double tilt_u = uniform(rng);
    const double offset_u = uniform(rng);
    const double gain_u = uniform(rng);
    test.push_back(DetectAll(surf, PlaceStrip(place, n, yaw, 0.8 + 0.4 * gain_u,
                                              20.0 * offset_u - 10.0, 1.5 * tilt_u, &rng)));
  }
  std::vector<double> nn_pos, nn_neg, ransac_pos, ransac_neg;
  int heading_ok = 0;
  for (int a = 0; a < places; ++a) {
    for (int b = 0; b < places; ++b) {
      LandmarkMatch m;
      ASSERT_EQ(matcher.Match(stored[static_cast<std::size_t>(a)],
                              test[static_cast<std::size_t>(b)], n, &m),
                Surf1dError::kOk);
      (a == b ? nn_pos : nn_neg).push_back(m.score);
      (a == b ? ransac_pos : ransac_neg).push_back(m.model_found ? m.ransac_score : 0.0);
      if (a == b && m.model_found) {
        double error = m.heading_offset_deg - yaws[static_cast<std::size_t>(a)] * 180.0 / kPi;
        error -= 360.0 * std::round(error / 360.0);
        if (std::abs(error) <= 2.0)
          ++heading_ok;
      }
    }
  }
  const double auc_nn = Auc(nn_pos, nn_neg);
  const double auc_ransac = Auc(ransac_pos, ransac_neg);
  std::printf(
      "1D SURF on %d synthetic places: AUC NN %.3f, NN with RANSAC %.3f (paper, real "
      "office images: 0.880 / 0.896); heading within 2 deg for %d/%d matched pairs\n",
      places, auc_nn, auc_ransac, heading_ok, places);
  RecordProperty("auc_nn", std::to_string(auc_nn));
  RecordProperty("auc_ransac", std::to_string(auc_ransac));
  EXPECT_GE(auc_ransac, 0.95);
  EXPECT_GE(auc_nn, 0.85);
  EXPECT_GE(heading_ok, places * 8 / 10);
}

TEST(Surf1dTest, RejectsBadOptionsAndSizes) {
  Surf1d surf;
  std::vector<float> s(360, 1.0f);
  std::vector<Surf1dFeature> f(8);
  int count = -1;
  EXPECT_EQ(surf.Detect(s, f, &count), Surf1dError::kNotInitialised);
  Surf1dOptions o;
  o.octaves = 0;
  EXPECT_EQ(surf.Init(360, o), Surf1dError::kBadOptions);
  o = {};
  o.threshold = -1.0f;
  EXPECT_EQ(surf.Init(360, o), Surf1dError::kBadOptions);
  EXPECT_EQ(surf.Init(147, Surf1dOptions{}), Surf1dError::kStripTooShort);
  ASSERT_EQ(surf.Init(148, Surf1dOptions{}), Surf1dError::kOk);
  EXPECT_EQ(surf.Detect(s, f, &count), Surf1dError::kSizeMismatch);
  EXPECT_NE(std::string(Surf1dErrorMessage(Surf1dError::kStripTooShort)).find("n_azimuth"),
            std::string::npos);

  LandmarkMatcher matcher;
  LandmarkMatch m;
  EXPECT_EQ(matcher.Match(f, f, 360, &m), Surf1dError::kNotInitialised);
  EXPECT_EQ(matcher.Init(0, LandmarkMatchOptions{}), Surf1dError::kBadOptions);
  ASSERT_EQ(matcher.Init(4, LandmarkMatchOptions{}), Surf1dError::kOk);
  EXPECT_EQ(matcher.Match(f, f, 360, &m), Surf1dError::kTooManyFeatures);
  // More stored features than the matcher holds, however few test ones.
  EXPECT_EQ(matcher.Match(f, std::span<const Surf1dFeature>(f).first(2), 360, &m),
            Surf1dError::kTooManyFeatures);
  // Default features have no Laplacian sign: not Detect's, refused.
  ASSERT_EQ(matcher.Init(8, LandmarkMatchOptions{}), Surf1dError::kOk);
  EXPECT_EQ(matcher.Match(f, f, 360, &m), Surf1dError::kBadFeature);
}

// The matcher as first written, straightforwardly: every stored feature tried in turn (the
// Laplacian sign compared on each), whole squared distances, every pair's residual folded in
// doubles, every line counted to the end. RANSAC's lines: when M matches give no more
// distinct lines M (M - 1) / 2 than ransac_iterations, the best of all of them by brute
// force (pairs i < j, anchored at i, in that order); otherwise the seeded random draws, all
// ransac_iterations of them. The fast matcher must give exactly its answers.
struct ReferenceMatch {
  LandmarkMatch result;
  std::vector<LandmarkMatcher::MatchedPair> pairs;
  bool every_line = false;  // RANSAC tried every distinct line
};

double ReferenceWrap(double x, double n) {
  return x - n * std::round(x / n);
}

double ReferenceFold(double x, double n, double half) {
  while (x > half)
    x -= n;
  while (x < -half)
    x += n;
  return x;
}

std::uint64_t ReferenceRandom(std::uint64_t* state) {
  std::uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

// The nearest two as the matcher first found them: every stored feature of the test
// feature's sign in the given order, the whole squared distance, a strictly smaller one
// replacing best. NearestTwo must give exactly its index (-1 when best is infinite) and
// both distances.
LandmarkMatcher::Nearest BruteNearestTwo(const std::vector<Surf1dFeature>& stored,
                                         const Surf1dFeature& t) {
  float best = std::numeric_limits<float>::infinity(), second = best;
  int index = -1;
  for (std::size_t s = 0; s < stored.size(); ++s) {
    if (stored[s].laplacian_sign != t.laplacian_sign)
      continue;
    float d = 0.0f;
    for (std::size_t k = 0; k < kSurf1dDescriptorSize; ++k) {
      const float e = stored[s].descriptor[k] - t.descriptor[k];
      d += e * e;
    }
    if (d < best) {
      second = best;
      best = d;
      index = static_cast<int>(s);
    } else if (d < second) {
      second = d;
    }
  }
  return {std::isinf(best) ? -1 : index, best, second};
}

ReferenceMatch ReferenceMatcher(const std::vector<Surf1dFeature>& stored,
                                const std::vector<Surf1dFeature>& test, int n,
                                const LandmarkMatchOptions& o) {
  ReferenceMatch out;
  LandmarkMatch& r = out.result;
  struct Pair {
    double xs, xt;
    float distance;
  };
  std::vector<Pair> pairs;
  for (const Surf1dFeature& t : test) {
    const LandmarkMatcher::Nearest nearest = BruteNearestTwo(stored, t);
    if (!std::isfinite(nearest.second) || !(nearest.best < o.ratio * o.ratio * nearest.second))
      continue;
    const float best = std::sqrt(nearest.best);
    pairs.push_back({static_cast<double>(stored[static_cast<std::size_t>(nearest.index)].position),
                     static_cast<double>(t.position), best});
    r.score += 1.0 / static_cast<double>(std::max(best, o.min_distance));
  }
  r.matches = static_cast<int>(pairs.size());
  for (const Pair& p : pairs)
    out.pairs.push_back({static_cast<int>(p.xs), static_cast<int>(p.xt), p.distance, false});
  if (r.matches < 2)
    return out;
  const double nd = n, half = 0.5 * nd;
  std::uint64_t state = o.seed;
  int best_inliers = 0;
  double best_residual = std::numeric_limits<double>::infinity();
  double best_scale = 1.0, best_displacement = 0.0;
  std::vector<bool> inlier(pairs.size()), best_inlier(pairs.size());
  const auto count = static_cast<std::uint64_t>(pairs.size());
  const auto line = [&](std::size_t i, std::size_t j) {
    const double ds = ReferenceFold(pairs[j].xs - pairs[i].xs, nd, half);
    const double dt = ReferenceFold(pairs[j].xt - pairs[i].xt, nd, half);
    if (ds == 0.0)
      return;
    const double scale = dt / ds;
    const auto max_scale = static_cast<double>(o.max_scale);
    if (!(scale >= 1.0 / max_scale && scale <= max_scale))
      return;
    int inliers = 0;
    double residual_sum = 0.0;
    for (std::size_t m = 0; m < pairs.size(); ++m) {
      const double predicted = scale * ReferenceFold(pairs[m].xs - pairs[i].xs, nd, half);
      const double residual = std::abs(
          ReferenceFold(ReferenceFold(pairs[m].xt - pairs[i].xt, nd, half) - predicted, nd, half));
      inlier[m] = residual <= static_cast<double>(o.inlier_threshold);
      if (inlier[m]) {
        ++inliers;
        residual_sum += residual;
      }
    }
    if (inliers > best_inliers || (inliers == best_inliers && residual_sum < best_residual)) {
      best_inliers = inliers;
      best_residual = residual_sum;
      best_scale = scale;
      best_displacement = ReferenceWrap(pairs[i].xt - scale * pairs[i].xs, nd);
      best_inlier = inlier;
    }
  };
  if (count * (count - 1) / 2 <= static_cast<std::uint64_t>(o.ransac_iterations)) {
    for (std::size_t i = 0; i < pairs.size(); ++i) {
      for (std::size_t j = i + 1; j < pairs.size(); ++j)
        line(i, j);
    }
    out.every_line = true;
  } else {
    for (int it = 0; it < o.ransac_iterations; ++it) {
      const auto i = static_cast<std::size_t>(ReferenceRandom(&state) % count);
      auto j = static_cast<std::size_t>(ReferenceRandom(&state) % (count - 1));
      if (j >= i)
        ++j;
      line(i, j);
    }
  }
  if (best_inliers < 2)
    return out;
  double reference = 0.0, sum = 0.0;
  bool have_reference = false;
  for (std::size_t m = 0; m < pairs.size(); ++m) {
    if (!best_inlier[m])
      continue;
    out.pairs[m].inlier = true;
    const double d = ReferenceWrap(pairs[m].xt - pairs[m].xs, nd);
    if (!have_reference) {
      reference = d;
      have_reference = true;
    }
    sum += reference + ReferenceWrap(d - reference, nd);
    r.ransac_score += 1.0 / static_cast<double>(std::max(pairs[m].distance, o.min_distance));
  }
  const double mean = ReferenceWrap(sum / best_inliers, nd);
  r.model_found = true;
  r.inliers = best_inliers;
  r.scale = best_scale;
  r.displacement = best_displacement;
  double degrees = mean * 360.0 / nd;
  if (degrees >= 180.0)
    degrees -= 360.0;
  r.heading_offset_deg = degrees;
  return out;
}

// Random features on n columns: `count` stored ones, and test ones of which a share are
// stored ones moved along a line (scale, shift) with noise on the position and the
// descriptor, the rest unrelated. Descriptors are coarse (multiples of 1/8 before scaling to
// unit length), so equal distances and ties between candidates happen.
void RandomFeatures(std::mt19937* rng, int n, int count, double scale, int shift,
                    std::vector<Surf1dFeature>* stored, std::vector<Surf1dFeature>* test) {
  std::uniform_int_distribution<int> column(0, n - 1), coarse(-8, 8), jitter(-2, 2), coin(0, 3);
  const auto descriptor = [&](Surf1dFeature* f) {
    float norm = 0.0f;
    for (float& v : f->descriptor) {
      v = static_cast<float>(coarse(*rng)) / 8.0f;
      norm += v * v;
    }
    if (norm > 0.0f) {
      for (float& v : f->descriptor)
        v /= std::sqrt(norm);
    }
  };
  stored->clear();
  test->clear();
  for (int k = 0; k < count; ++k) {
    Surf1dFeature f;
    f.position = column(*rng);
    f.laplacian_sign = coin(*rng) < 2 ? std::int8_t{1} : std::int8_t{-1};
    descriptor(&f);
    stored->push_back(f);
    Surf1dFeature g = f;
    if (coin(*rng) == 0) {  // unrelated
      g.position = column(*rng);
      descriptor(&g);
    } else {
      const double moved = scale * f.position + shift + jitter(*rng);
      g.position = ((static_cast<int>(std::lround(moved)) % n) + n) % n;
      if (coin(*rng) == 0)
        g.descriptor[static_cast<std::size_t>(coin(*rng))] += 0.05f;
    }
    test->push_back(g);
  }
  std::shuffle(test->begin(), test->end(), *rng);
}

void ExpectSameMatch(const LandmarkMatcher& matcher, const LandmarkMatch& m,
                     const ReferenceMatch& want, const std::string& where) {
  SCOPED_TRACE(where);
  EXPECT_EQ(m.matches, want.result.matches);
  EXPECT_EQ(m.score, want.result.score);
  EXPECT_EQ(m.model_found, want.result.model_found);
  EXPECT_EQ(m.inliers, want.result.inliers);
  EXPECT_EQ(m.ransac_score, want.result.ransac_score);
  EXPECT_EQ(m.scale, want.result.scale);
  EXPECT_EQ(m.displacement, want.result.displacement);
  EXPECT_EQ(m.heading_offset_deg, want.result.heading_offset_deg);
  ASSERT_EQ(matcher.last_pair_count(), static_cast<int>(want.pairs.size()));
  for (int i = 0; i < matcher.last_pair_count(); ++i) {
    const LandmarkMatcher::MatchedPair p = matcher.last_pair(i);
    const LandmarkMatcher::MatchedPair& q = want.pairs[static_cast<std::size_t>(i)];
    EXPECT_EQ(p.x_stored, q.x_stored) << i;
    EXPECT_EQ(p.x_test, q.x_test) << i;
    EXPECT_EQ(p.distance, q.distance) << i;
    EXPECT_EQ(p.inlier, q.inlier) << i;
  }
}

// The matcher's early exits (partial distances, lines that cannot win, a perfect line) and
// its integer folds give the straightforward matcher's answers exactly, on random feature
// sets of every size from none to full, on even and odd strip lengths, several options:
// every distinct line when there are few, and the random draws.
TEST(Surf1dTest, MatcherEqualsTheStraightforwardMatcher) {
  std::mt19937 rng(2026);
  int with_model = 0, cases = 0, every_line = 0;
  for (const int n : {360, 361, 200}) {
    for (const int count : {0, 1, 2, 3, 10, 20, 21, 30, 60, 256}) {
      for (int trial = 0; trial < 9; ++trial) {
        LandmarkMatchOptions o;
        o.seed = static_cast<std::uint64_t>(trial + 1);
        if (trial % 3 == 1) {
          o.ratio = 0.9f;
          o.inlier_threshold = 0.0f;
          o.max_scale = 2.0f;
        } else if (trial % 3 == 2) {
          o.ransac_iterations = 37;
          o.inlier_threshold = 5.5f;
        }
        const double scale = trial % 2 == 0 ? 1.0 : 1.1;
        std::vector<Surf1dFeature> stored, test;
        RandomFeatures(&rng, n, count, scale, 17 + 41 * trial, &stored, &test);
        LandmarkMatcher matcher;
        ASSERT_EQ(matcher.Init(256, o), Surf1dError::kOk);
        LandmarkMatch m;
        ASSERT_EQ(matcher.Match(stored, test, n, &m), Surf1dError::kOk);
        const ReferenceMatch want = ReferenceMatcher(stored, test, n, o);
        ExpectSameMatch(matcher, m, want,
                        "n " + std::to_string(n) + " count " + std::to_string(count) + " trial " +
                            std::to_string(trial));
        with_model += want.result.model_found ? 1 : 0;
        every_line += want.every_line && want.result.matches >= 3 ? 1 : 0;
        ++cases;
      }
    }
  }
  // The sets exercise both outcomes.
  EXPECT_GT(with_model, cases / 3);
  EXPECT_LT(with_model, cases);
  std::printf("%d cases: %d with a model, %d tried every line (>= 3 matches)\n", cases, with_model,
              every_line);
  EXPECT_GT(every_line, cases / 10);
}

// The same on features Detect found on strips turned and rescaled against each other, and
// on a perfect turn (every pair on the line: RANSAC may stop at once).
TEST(Surf1dTest, MatcherEqualsTheStraightforwardMatcherOnDetectedFeatures) {
  const int n = 360;
  Surf1d surf;
  ASSERT_EQ(surf.Init(n, Surf1dOptions{}), Surf1dError::kOk);
  LandmarkMatcher matcher;
  ASSERT_EQ(matcher.Init(512, LandmarkMatchOptions{}), Surf1dError::kOk);
  for (unsigned seed = 1; seed <= 6; ++seed) {
    const std::vector<float> a = IntegerStrip(n, seed);
    std::vector<float> b = Shifted(a, static_cast<int>(37 * seed));
    if (seed % 2 == 0)
      b = IntegerStrip(n, seed + 100);  // unrelated
    if (seed == 5) {
      for (std::size_t k = 0; k < b.size(); k += 7)
        b[k] += 9.0f;  // turned, with local damage
    }
    const std::vector<Surf1dFeature> fa = DetectAll(surf, a), fb = DetectAll(surf, b);
    LandmarkMatch m;
    ASSERT_EQ(matcher.Match(fa, fb, n, &m), Surf1dError::kOk);
    ExpectSameMatch(matcher, m, ReferenceMatcher(fa, fb, n, LandmarkMatchOptions{}),
                    "seed " + std::to_string(seed));
  }
}

// SetStored once, then MatchStored against several queries: the answers of Match.
TEST(Surf1dTest, StoredFeaturesHeldAcrossMatches) {
  std::mt19937 rng(7);
  std::vector<Surf1dFeature> stored, test, other_stored, other_test;
  RandomFeatures(&rng, 360, 120, 1.0, 30, &stored, &test);
  RandomFeatures(&rng, 360, 120, 1.0, 90, &other_stored, &other_test);
  LandmarkMatcher held, fresh;
  ASSERT_EQ(held.Init(256, LandmarkMatchOptions{}), Surf1dError::kOk);
  ASSERT_EQ(fresh.Init(256, LandmarkMatchOptions{}), Surf1dError::kOk);
  LandmarkMatch m, want;
  EXPECT_EQ(held.MatchStored(test, 360, &m), Surf1dError::kNotInitialised);
  ASSERT_EQ(held.SetStored(stored), Surf1dError::kOk);
  for (const auto* query : {&test, &other_test, &test}) {
    ASSERT_EQ(held.MatchStored(*query, 360, &m), Surf1dError::kOk);
    ASSERT_EQ(fresh.Match(stored, *query, 360, &want), Surf1dError::kOk);
    EXPECT_EQ(m.matches, want.matches);
    EXPECT_EQ(m.inliers, want.inliers);
    EXPECT_EQ(m.heading_offset_deg, want.heading_offset_deg);
    EXPECT_EQ(m.ransac_score, want.ransac_score);
  }
  EXPECT_TRUE(m.model_found);
  // A feature not from Detect (no Laplacian sign) is refused, and holds nothing.
  std::vector<Surf1dFeature> unsigned_features = stored;
  unsigned_features[3].laplacian_sign = 0;
  EXPECT_EQ(held.SetStored(unsigned_features), Surf1dError::kBadFeature);
  EXPECT_EQ(held.MatchStored(test, 360, &m), Surf1dError::kNotInitialised);
  ASSERT_EQ(held.SetStored(stored), Surf1dError::kOk);
  EXPECT_EQ(held.MatchStored(unsigned_features, 360, &m), Surf1dError::kBadFeature);
  EXPECT_NE(std::string(Surf1dErrorMessage(Surf1dError::kBadFeature)).find("Detect"),
            std::string::npos);
}

// The search walks out from the test feature's key and stops early; on random and on
// adversarial stored sets (coarse values with many equal distances, duplicated features,
// every feature the same, one candidate of a sign, none, keys all equal, distances that
// overflow, components that are not finite) it gives the brute force's nearest two to the
// bit, the first index of equals included. Counted: cases where best ties another feature
// at a larger index (the tie-break mattered), and none of a sign.
TEST(Surf1dTest, NearestTwoEqualsTheBruteForce) {
  std::mt19937 rng(33);
  std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
  std::uniform_int_distribution<int> coarse(-3, 3), coin(0, 1);
  const float inf = std::numeric_limits<float>::infinity();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  LandmarkMatcher matcher;
  ASSERT_EQ(matcher.Init(300, LandmarkMatchOptions{}), Surf1dError::kOk);
  int cases = 0, tied = 0, none = 0, found = 0;
  const auto check = [&](const std::vector<Surf1dFeature>& stored,
                         const std::vector<Surf1dFeature>& tests, const std::string& where) {
    SCOPED_TRACE(where);
    ASSERT_EQ(matcher.SetStored(stored), Surf1dError::kOk);
    for (const Surf1dFeature& t : tests) {
      const LandmarkMatcher::Nearest got = matcher.NearestTwo(t);
      const LandmarkMatcher::Nearest want = BruteNearestTwo(stored, t);
      ASSERT_EQ(got.index, want.index);
      // Bits, so NaN and -0 compare too.
      ASSERT_EQ(std::bit_cast<std::uint32_t>(got.best), std::bit_cast<std::uint32_t>(want.best));
      ASSERT_EQ(std::bit_cast<std::uint32_t>(got.second),
                std::bit_cast<std::uint32_t>(want.second));
      ++cases;
      found += want.index >= 0 ? 1 : 0;
      none +=
          std::none_of(stored.begin(), stored.end(),
                       [&](const Surf1dFeature& f) { return f.laplacian_sign == t.laplacian_sign; })
              ? 1
              : 0;
      if (want.index >= 0 && want.best == want.second) {
        for (std::size_t s = static_cast<std::size_t>(want.index) + 1; s < stored.size(); ++s) {
          if (stored[s].laplacian_sign == t.laplacian_sign &&
              BruteNearestTwo({stored[s]}, t).best == want.best) {
            ++tied;
            break;
          }
        }
      }
    }
  };
  const auto feature = [&](bool coarse_values, std::int8_t sign) {
    Surf1dFeature f;
    f.position = static_cast<int>(rng() % 360);
    f.laplacian_sign = sign;
    for (float& v : f.descriptor)
      v = coarse_values ? static_cast<float>(coarse(rng)) / 4.0f : uniform(rng);
    return f;
  };
  const auto random_sign = [&] { return coin(rng) == 0 ? std::int8_t{1} : std::int8_t{-1}; };
  for (const int count : {0, 1, 2, 3, 4, 5, 7, 8, 9, 31, 64, 129, 300}) {
    for (int trial = 0; trial < 6; ++trial) {
      const bool coarse_values = trial % 2 == 1;
      std::vector<Surf1dFeature> stored, tests;
      for (int i = 0; i < count; ++i) {
        // trial 2, 3: every stored feature of one sign, so none of the other
        stored.push_back(feature(coarse_values, trial / 2 == 1 ? std::int8_t{1} : random_sign()));
        if (trial >= 4 && i > 0 && coin(rng) == 0)
          stored.back().descriptor = stored[rng() % stored.size()].descriptor;  // a duplicate
      }
      for (int i = 0; i < 60; ++i)
        tests.push_back(feature(coarse_values, random_sign()));
      for (const Surf1dFeature& f : stored) {  // at distance 0 from a stored one, and near
        tests.push_back(f);
        tests.push_back(f);
        tests.back().descriptor[rng() % kSurf1dDescriptorSize] += 0.01f;
      }
      check(stored, tests, "count " + std::to_string(count) + " trial " + std::to_string(trial));
    }
  }
  // Every stored feature the same: best == second, the first index must win.
  std::vector<Surf1dFeature> same(40, feature(false, 1));
  check(same, {same[0], feature(false, 1), feature(false, -1)}, "all the same");
  // One candidate of each sign.
  std::vector<Surf1dFeature> one = {feature(false, 1), feature(false, -1)};
  check(one, {feature(false, 1), feature(false, -1), one[0]}, "one candidate");
  // Keys all equal: the first component equal everywhere, the rest in a narrower range.
  std::vector<Surf1dFeature> flat;
  for (int i = 0; i < 50; ++i) {
    flat.push_back(feature(true, 1));
    for (float& v : flat.back().descriptor)
      v = 0.5f;
    flat.back().descriptor[1 + static_cast<std::size_t>(i % 5)] = 0.25f * static_cast<float>(i % 3);
  }
  check(flat, {feature(true, 1), feature(false, 1), flat[7]}, "keys equal");
  // Large values: some distances overflow to infinity (all of them for the far test).
  std::vector<Surf1dFeature> large;
  for (int i = 0; i < 30; ++i) {
    large.push_back(feature(false, 1));
    for (float& v : large.back().descriptor)
      v *= 3e38f;
  }
  Surf1dFeature far = feature(false, 1);
  far.descriptor.fill(-3e38f);
  check(large, {far, large[3], feature(false, 1)}, "overflow");
  // Components that are not finite, stored and test: the scan's NaN rules.
  std::vector<Surf1dFeature> odd;
  for (int i = 0; i < 20; ++i)
    odd.push_back(feature(false, 1));
  odd[4].descriptor[2] = nan;
  odd[9].descriptor[0] = inf;
  odd[13].descriptor[5] = -inf;
  Surf1dFeature test_nan = feature(false, 1), test_inf = feature(false, 1);
  test_nan.descriptor[3] = nan;
  test_inf.descriptor[0] = inf;
  check(odd, {feature(false, 1), odd[2], test_nan, test_inf}, "not finite, stored");
  std::vector<Surf1dFeature> plain(odd.begin(), odd.begin() + 4);
  check(plain, {test_nan, test_inf, feature(false, 1)}, "not finite, test");
  std::printf(
      "%d test features: %d with a nearest, %d tied at best with a later index, %d of a "
      "sign with no candidates\n",
      cases, found, tied, none);
  EXPECT_GT(tied, 100);
  EXPECT_GT(none, 100);
  EXPECT_GT(found, cases / 2);
}

// The search stops early once the ratio test is sure to pass; at every ratio, above 1 too
// (where a nearer feature could still be left when the test already holds), the matcher
// gives the straightforward matcher's pairs.
TEST(Surf1dTest, MatcherEqualsTheStraightforwardMatcherAtAnyRatio) {
  std::mt19937 rng(34);
  int pairs = 0;
  for (const float ratio : {0.3f, 0.7f, 1.0f, 1.5f, 4.0f}) {
    for (const int count : {2, 9, 64, 256}) {
      for (int trial = 0; trial < 4; ++trial) {
        LandmarkMatchOptions o;
        o.ratio = ratio;
        std::vector<Surf1dFeature> stored, test;
        RandomFeatures(&rng, 360, count, 1.0, 40 + trial, &stored, &test);
        if (trial % 2 == 1) {  // continuous descriptors: fewer ties, other stops
          std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
          for (auto* features : {&stored, &test}) {
            for (Surf1dFeature& f : *features) {
              for (float& v : f.descriptor)
                v = uniform(rng);
            }
          }
        }
        LandmarkMatcher matcher;
        ASSERT_EQ(matcher.Init(256, o), Surf1dError::kOk);
        LandmarkMatch m;
        ASSERT_EQ(matcher.Match(stored, test, 360, &m), Surf1dError::kOk);
        const ReferenceMatch want = ReferenceMatcher(stored, test, 360, o);
        ExpectSameMatch(matcher, m, want,
                        "ratio " + std::to_string(ratio) + " count " + std::to_string(count) +
                            " trial " + std::to_string(trial));
        pairs += want.result.matches;
      }
    }
  }
  EXPECT_GT(pairs, 1000);
}

// The detector as first written: the integral summed from -pad as Detect sums it (so the
// responses are the same bits), the candidates layer by layer with the weakest replaced when
// the buffer is full, std::sort by position then layer, and each descriptor's 15 samples as
// two BoxSums each. Detect must give exactly its features, in its order.
std::vector<Surf1dFeature> ReferenceDetect(const std::vector<float>& strip, const Surf1dOptions& o,
                                           std::size_t capacity, int* dropped) {
  const long n = static_cast<long>(strip.size());
  std::vector<long> lobes;
  for (int oc = 0; oc < o.octaves; ++oc) {
    for (int i = 0; i < o.intervals; ++i)
      lobes.push_back((2L << oc) * (i + 1) + 1);
  }
  std::sort(lobes.begin(), lobes.end());
  lobes.erase(std::unique(lobes.begin(), lobes.end()), lobes.end());
  const long max_lobe = lobes.back();
  const auto step_of = [](long lobe) {
    return std::max(1L, std::lround(0.4 * static_cast<double>(lobe)));
  };
  const long pad = std::max<long>((3 * max_lobe + 1) / 2 + 1, 8 * step_of(max_lobe) + 1);
  std::vector<double> integral(static_cast<std::size_t>(n + 2 * pad) + 1, 0.0);
  double running = 0.0;
  for (std::size_t i = 1; i < integral.size(); ++i) {
    const long column = ((static_cast<long>(i) - 1 - pad) % n + n) % n;
    running += static_cast<double>(strip[static_cast<std::size_t>(column)]);
    integral[i] = running;
  }
  const auto box = [&](long a, long b) {
    return integral[static_cast<std::size_t>(b + pad)] -
           integral[static_cast<std::size_t>(a + pad)];
  };
  const auto layers = static_cast<long>(lobes.size());
  std::vector<float> response(static_cast<std::size_t>(layers * n));
  for (long li = 0; li < layers; ++li) {
    const long l = lobes[static_cast<std::size_t>(li)], h = (l - 1) / 2;
    for (long x = 0; x < n; ++x) {
      response[static_cast<std::size_t>(li * n + x)] = static_cast<float>(
          (box(x - h - l, x - h) + box(x + h + 1, x + h + 1 + l) - 2.0 * box(x - h, x + h + 1)) /
          static_cast<double>(l));
    }
  }
  const auto magnitude = [&](long li, long x) {
    return std::abs(response[static_cast<std::size_t>(li * n + (x + n) % n)]);
  };
  std::vector<Surf1dFeature> kept;
  *dropped = 0;
  for (long li = 0; li < layers; ++li) {
    for (long x = 0; x < n; ++x) {
      const float m = magnitude(li, x);
      if (!(m > o.threshold) || !(m > magnitude(li, x - 1) && m >= magnitude(li, x + 1)))
        continue;
      bool is_max = true;
      for (long dx = -1; dx <= 1 && o.suppress_across_scale; ++dx) {
        if (li > 0 && !(m > magnitude(li - 1, x + dx)))
          is_max = false;
        if (li + 1 < layers && !(m >= magnitude(li + 1, x + dx)))
          is_max = false;
      }
      if (!is_max)
        continue;
      Surf1dFeature f;
      f.position = static_cast<std::int32_t>(x);
      f.layer = static_cast<std::int32_t>(li);
      f.lobe = static_cast<std::int32_t>(lobes[static_cast<std::size_t>(li)]);
      f.response = response[static_cast<std::size_t>(li * n + x)];
      f.laplacian_sign = f.response > 0.0f ? std::int8_t{1} : std::int8_t{-1};
      if (kept.size() < capacity) {
        kept.push_back(f);
        continue;
      }
      ++*dropped;
      if (kept.empty())
        continue;
      auto weakest = std::min_element(kept.begin(), kept.end(), [](const auto& a, const auto& b) {
        return std::abs(a.response) < std::abs(b.response);
      });
      if (std::abs(weakest->response) < m)
        *weakest = f;
    }
  }
  std::sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) {
    return a.position != b.position ? a.position < b.position : a.layer < b.layer;
  });
  for (Surf1dFeature& f : kept) {
    const long step = step_of(f.lobe);
    std::array<double, kSurf1dDescriptorSize> v{};
    for (long k = -7; k <= 7; ++k) {
      const long p = f.position + k * step;
      const double dx = (box(p, p + step) - box(p - step, p)) / static_cast<double>(step);
      const double kk = static_cast<double>(k);
      const double w = std::exp(-kk * kk / (2.0 * 2.5 * 2.5));
      const auto sub = static_cast<std::size_t>((k + 7) / 5);
      v[2 * sub] += w * dx;
      v[2 * sub + 1] += w * std::abs(dx);
    }
    double norm = 0.0;
    for (const double x : v)
      norm += x * x;
    norm = std::sqrt(norm);
    for (std::size_t i = 0; i < v.size(); ++i)
      f.descriptor[i] = norm > 0.0 ? static_cast<float>(v[i] / norm) : 0.0f;
  }
  return kept;
}

// Detect's features are the first-written detector's to the bit, in the same order: on
// integer and fractional strips, with the default and other options, and with buffers too
// small for all the candidates (the strongest kept, which may then be any of them).
TEST(Surf1dTest, DetectEqualsTheStraightforwardDetector) {
  std::mt19937 rng(33);
  std::uniform_real_distribution<float> fraction(0.0f, 1.0f);
  std::uniform_int_distribution<int> exponent(-12, 12);
  int cases = 0, overflowed = 0;
  for (const int n : {360, 361, 200}) {
    for (unsigned seed = 1; seed <= 4; ++seed) {
      std::vector<float> strip = IntegerStrip(n, seed);
      if (seed % 2 == 0) {
        for (float& x : strip)  // magnitudes 2^-12..2^20: the integral's sums round
          x = std::ldexp(x * (1.0f + fraction(rng)), exponent(rng));
      }
      for (int variant = 0; variant < 3; ++variant) {
        Surf1dOptions o;
        if (variant == 1) {
          o.suppress_across_scale = true;
          o.threshold = 0.5f;
        } else if (variant == 2) {
          o.octaves = 3;
          o.intervals = 4;
        }
        Surf1d surf;
        ASSERT_EQ(surf.Init(n, o), Surf1dError::kOk);
        for (const std::size_t capacity : {std::size_t{512}, std::size_t{40}, std::size_t{0}}) {
          SCOPED_TRACE("n " + std::to_string(n) + " seed " + std::to_string(seed) + " variant " +
                       std::to_string(variant) + " capacity " + std::to_string(capacity));
          int want_dropped = 0;
          const std::vector<Surf1dFeature> want =
              ReferenceDetect(strip, o, capacity, &want_dropped);
          std::vector<Surf1dFeature> got(capacity);
          int count = -1;
          ASSERT_EQ(surf.Detect(strip, got, &count), Surf1dError::kOk);
          ASSERT_EQ(count, static_cast<int>(want.size()));
          EXPECT_EQ(surf.dropped(), want_dropped);
          for (std::size_t i = 0; i < want.size(); ++i) {
            EXPECT_EQ(got[i].position, want[i].position) << i;
            EXPECT_EQ(got[i].layer, want[i].layer) << i;
            EXPECT_EQ(got[i].lobe, want[i].lobe) << i;
            EXPECT_EQ(got[i].response, want[i].response) << i;
            EXPECT_EQ(got[i].laplacian_sign, want[i].laplacian_sign) << i;
            EXPECT_EQ(got[i].descriptor, want[i].descriptor) << i;
          }
          overflowed += want_dropped > 0 ? 1 : 0;
          ++cases;
        }
      }
    }
  }
  // Both paths: every candidate kept, and the buffer full.
  EXPECT_GT(overflowed, cases / 3);
  EXPECT_LT(overflowed, cases);
}

// A full buffer keeps the strongest features.
TEST(Surf1dTest, OverflowKeepsTheStrongest) {
  const std::vector<float> s = IntegerStrip(360, 7);
  Surf1d surf;
  ASSERT_EQ(surf.Init(360, Surf1dOptions{}), Surf1dError::kOk);
  std::vector<Surf1dFeature> all = DetectAll(surf, s);
  ASSERT_GT(all.size(), 10u);
  std::vector<Surf1dFeature> few(10);
  int count = 0;
  ASSERT_EQ(surf.Detect(s, few, &count), Surf1dError::kOk);
  EXPECT_EQ(count, 10);
  EXPECT_EQ(surf.dropped(), static_cast<int>(all.size()) - 10);
  std::vector<float> strengths;
  for (const auto& g : all)
    strengths.push_back(std::abs(g.response));
  std::sort(strengths.rbegin(), strengths.rend());
  for (const auto& g : few)
    EXPECT_GE(std::abs(g.response), strengths[9]);
  EXPECT_TRUE(std::is_sorted(few.begin(), few.end(),
                             [](const auto& a, const auto& b) { return a.position < b.position; }));
}

TEST(Surf1dTest, DetectAndMatchAllocateNothing) {
  ASSERT_TRUE(AllocationCounterActive());
  const std::vector<float> a = IntegerStrip(360, 1);
  const std::vector<float> b = Shifted(a, 40);
  Surf1d surf;
  ASSERT_EQ(surf.Init(360, Surf1dOptions{}), Surf1dError::kOk);
  LandmarkMatcher matcher;
  ASSERT_EQ(matcher.Init(256, LandmarkMatchOptions{}), Surf1dError::kOk);
  std::vector<Surf1dFeature> fa(256), fb(256);
  int na = 0, nb = 0;
  LandmarkMatch m;
  AllocationScope scope;
  ASSERT_EQ(surf.Detect(a, fa, &na), Surf1dError::kOk);
  ASSERT_EQ(surf.Detect(b, fb, &nb), Surf1dError::kOk);
  ASSERT_EQ(matcher.Match(std::span(fa).first(static_cast<std::size_t>(na)),
                          std::span(fb).first(static_cast<std::size_t>(nb)), 360, &m),
            Surf1dError::kOk);
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_TRUE(m.model_found);
}

}  // namespace
}  // namespace skyloc::dsp
