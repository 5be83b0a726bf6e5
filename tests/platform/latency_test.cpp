// Latency percentiles against hand-computed nearest-rank values of known sample sets.
#include "skyloc/platform/latency.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <vector>

namespace skyloc {
namespace {

using std::chrono::microseconds;
using std::chrono::nanoseconds;

TEST(LatencyHistogram, EmptyReportsZero) {
  LatencyHistogram h;
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.Percentile(50).count(), 0);
  EXPECT_EQ(h.max().count(), 0);
}

TEST(LatencyHistogram, SmallValuesAreExact) {
  // Sorted: 1 3 5 7 9. Nearest rank: p50 -> ceil(2.5) = 3rd = 5; p99 -> 5th = 9;
  // p20 -> 1st = 1; p40 -> 2nd = 3.
  LatencyHistogram h;
  for (int v : {9, 1, 5, 3, 7})
    h.Record(nanoseconds(v));
  EXPECT_EQ(h.count(), 5u);
  EXPECT_EQ(h.Percentile(50).count(), 5);
  EXPECT_EQ(h.Percentile(99).count(), 9);
  EXPECT_EQ(h.Percentile(20).count(), 1);
  EXPECT_EQ(h.Percentile(40).count(), 3);
  EXPECT_EQ(h.max().count(), 9);
}

TEST(LatencyHistogram, MicrosecondSamplesWithinOneSixtyFourth) {
  // 1, 2, ..., 100 us: p50 = 50 us, p99 = 99 us, p90 = 90 us, max = 100 us (exact).
  LatencyHistogram h;
  for (int i = 100; i >= 1; --i)
    h.Record(microseconds(i));
  struct {
    double p;
    double want_ns;
  } cases[] = {{50, 50000}, {90, 90000}, {99, 99000}, {100, 100000}};
  for (const auto& c : cases) {
    const double got = static_cast<double>(h.Percentile(c.p).count());
    EXPECT_GE(got, c.want_ns) << "p" << c.p;
    EXPECT_LE(got, c.want_ns * (1.0 + 1.0 / 64)) << "p" << c.p;
  }
  EXPECT_EQ(h.max(), microseconds(100));
  EXPECT_EQ(h.Percentile(100), microseconds(100));
}

TEST(LatencyHistogram, OutlierDoesNotMoveTheMedian) {
  // 99 samples of 200 us and one of 5 ms: p50 = p99 = 200 us, max = 5 ms.
  LatencyHistogram h;
  for (int i = 0; i < 99; ++i)
    h.Record(microseconds(200));
  h.Record(microseconds(5000));
  EXPECT_NEAR(static_cast<double>(h.Percentile(50).count()), 200000.0, 200000.0 / 64);
  EXPECT_NEAR(static_cast<double>(h.Percentile(99).count()), 200000.0, 200000.0 / 64);
  EXPECT_EQ(h.max(), microseconds(5000));
}

TEST(LatencyHistogram, AgreesWithSortingOnRandomSamples) {
  std::mt19937_64 rng(3);
  std::lognormal_distribution<double> dist(11.0, 1.0);  // median ~60 us
  std::vector<std::int64_t> samples;
  LatencyHistogram h;
  for (int i = 0; i < 10000; ++i) {
    const auto v = static_cast<std::int64_t>(dist(rng));
    samples.push_back(v);
    h.Record(nanoseconds(v));
  }
  std::sort(samples.begin(), samples.end());
  for (double p : {1.0, 25.0, 50.0, 90.0, 99.0, 99.9}) {
    const auto rank = static_cast<std::size_t>(std::ceil(p / 100.0 * 10000.0));
    const double want = static_cast<double>(samples[rank - 1]);
    const double got = static_cast<double>(h.Percentile(p).count());
    EXPECT_GE(got, want) << p;
    EXPECT_LE(got, want * (1.0 + 1.0 / 64) + 1) << p;
  }
}

TEST(LatencyHistogram, BucketEdgesAreContiguous) {
  for (std::size_t b = 0; b + 1 < LatencyHistogram::kBuckets; ++b) {
    const std::uint64_t edge = LatencyHistogram::BucketUpperEdge(b);
    ASSERT_EQ(LatencyHistogram::BucketOf(edge), b) << b;
    ASSERT_EQ(LatencyHistogram::BucketOf(edge + 1), b + 1) << b;
  }
}

TEST(LatencyTable, RecordsPerStageAndPrints) {
  LatencyTable t;
  const int a = t.AddStage("capture");
  const int b = t.AddStage("seqslam");
  ManualClock clock;
  {
    StageTimer timer(t, a, clock);
    clock.Advance(microseconds(30));
  }
  t.Record(b, microseconds(7));
  t.Record(b, microseconds(9));
  EXPECT_EQ(t.stage(a).count(), 1u);
  EXPECT_EQ(t.stage(a).max(), microseconds(30));
  EXPECT_EQ(t.stage(b).count(), 2u);
  char buffer[512] = {};
  std::FILE* f = fmemopen(buffer, sizeof buffer - 1, "w");
  ASSERT_NE(f, nullptr);
  t.Print(f);
  std::fclose(f);
  const std::string text = buffer;
  EXPECT_NE(text.find("p99_us"), std::string::npos) << text;
  EXPECT_NE(text.find("capture               1       30.0       30.0       30.0"),
            std::string::npos)
      << text;
}

}  // namespace
}  // namespace skyloc
