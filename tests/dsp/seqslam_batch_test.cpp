// The blocked batch engine (seqslam_batch.h) against the whole-matrix batch engine: the
// same floats, bit for bit, whatever the block size and however the work is split.
#include "skyloc/dsp/seqslam_batch.h"

#include <gtest/gtest.h>

#include <cstdlib>
#include <limits>
#include <random>
#include <vector>

#include "support/synthetic_descriptors.h"

namespace skyloc::dsp {
namespace {

std::vector<float> RandomFloats(std::size_t n, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g(0.0f, 2.0f);
  std::vector<float> v(n);
  for (float& x : v)
    x = g(rng);
  return v;
}

void ExpectSameMatches(std::span<const SeqSlamMatch> a, std::span<const SeqSlamMatch> b,
                       const char* what) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t t = 0; t < a.size(); ++t) {
    ASSERT_EQ(a[t].valid, b[t].valid) << what << " t " << t;
    if (!a[t].valid)
      continue;
    EXPECT_EQ(a[t].reference, b[t].reference) << what << " t " << t;
    EXPECT_EQ(a[t].start, b[t].start) << what << " t " << t;
    EXPECT_EQ(a[t].velocity, b[t].velocity) << what << " t " << t;
    // Bit for bit: EXPECT_EQ on floats is exact.
    EXPECT_EQ(a[t].score, b[t].score) << what << " t " << t;
    EXPECT_EQ(a[t].uniqueness, b[t].uniqueness) << what << " t " << t;
    EXPECT_EQ(a[t].confidence, b[t].confidence) << what << " t " << t;
  }
}

// Every entry of a tile is DifferenceColumn's float, for descriptor lengths with and
// without a tail of < 8 elements, odd and even tile sizes and offsets.
TEST(SeqSlamBatchBlocked, FloatTileEqualsDifferenceColumn) {
  for (const int dim : {1, 7, 8, 13, 120, 2048}) {
    const int n_ref = 37, n_query = 9;
    const std::vector<float> ref = RandomFloats(static_cast<std::size_t>(n_ref * dim), 1);
    const std::vector<float> query = RandomFloats(static_cast<std::size_t>(n_query * dim), 2);
    std::vector<float> column(static_cast<std::size_t>(n_ref));
    const DescriptorRows r = DescriptorRows::Floats(ref, dim),
                         q = DescriptorRows::Floats(query, dim);
    const int r0 = 3, r1 = 36, q0 = 1, q1 = 8;
    std::vector<float> tile(static_cast<std::size_t>((r1 - r0) * (q1 - q0)));
    DifferenceTile(r, q, r0, r1, q0, q1, tile.data(), static_cast<std::size_t>(r1 - r0));
    for (int t = q0; t < q1; ++t) {
      DifferenceColumn(ref, dim,
                       std::span<const float>(query).subspan(static_cast<std::size_t>(t * dim),
                                                             static_cast<std::size_t>(dim)),
                       column);
      for (int k = r0; k < r1; ++k) {
        ASSERT_EQ(tile[static_cast<std::size_t>((t - q0) * (r1 - r0) + (k - r0))],
                  column[static_cast<std::size_t>(k)])
            << "dim " << dim << " query " << t << " reference " << k;
      }
    }
  }
}

// Bytes: the exact integer sum of absolute differences over 16 x dim.
TEST(SeqSlamBatchBlocked, ByteTileIsTheIntegerSad) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> byte(0, 255);
  for (const int dim : {1, 15, 16, 33, 2048, 4100}) {
    const int n_ref = 11, n_query = 5;
    std::vector<std::uint8_t> ref(static_cast<std::size_t>(n_ref * dim)),
        query(static_cast<std::size_t>(n_query * dim));
    for (auto& b : ref)
      b = static_cast<std::uint8_t>(byte(rng));
    for (auto& b : query)
      b = static_cast<std::uint8_t>(byte(rng));
    std::vector<float> tile(static_cast<std::size_t>(n_ref * n_query));
    DifferenceTile(DescriptorRows::Bytes(ref, dim), DescriptorRows::Bytes(query, dim), 0, n_ref, 0,
                   n_query, tile.data(), static_cast<std::size_t>(n_ref));
    for (int t = 0; t < n_query; ++t) {
      for (int k = 0; k < n_ref; ++k) {
        long sad = 0;
        for (int i = 0; i < dim; ++i) {
          sad += std::abs(int{ref[static_cast<std::size_t>(k * dim + i)]} -
                          int{query[static_cast<std::size_t>(t * dim + i)]});
        }
        const float expected = static_cast<float>(sad) * (1.0f / (16.0f * static_cast<float>(dim)));
        ASSERT_EQ(tile[static_cast<std::size_t>(t * n_ref + k)], expected)
            << "dim " << dim << " query " << t << " reference " << k;
      }
    }
  }
}

TEST(SeqSlamBatchBlocked, QuantiseRoundsAndClamps) {
  const float in[] = {0.0f, 1.0f / 32, -1.0f / 32, 7.875f, -7.875f, 100.0f, -100.0f, 0.1f};
  std::uint8_t out[8];
  QuantiseToBytes(in, out);
  EXPECT_EQ(out[0], 128);
  EXPECT_EQ(out[1], 129);  // a half step rounds up
  EXPECT_EQ(out[2], 128);
  EXPECT_EQ(out[3], 254);  // the largest z-score of an 8x8 patch does not clip
  EXPECT_EQ(out[4], 2);
  EXPECT_EQ(out[5], 255);
  EXPECT_EQ(out[6], 0);
  EXPECT_EQ(out[7], 130);  // 1.6 -> 2
}

// The blocked engine gives BatchSeqSlam's matches bit for bit, for block sizes from one
// column to more than the run, both windows and several sequence lengths.
TEST(SeqSlamBatchBlocked, EqualsWholeMatrixEngineForEveryBlockSize) {
  testing::SyntheticRoute route;
  route.dim = 120;
  const int n_ref = 300, n_query = 90;
  const std::vector<float> ref = route.Reference(n_ref);
  const std::vector<float> query = route.Query(n_query, n_ref, 40.0, 1.1, 1.5f);
  for (const int ds : {1, 4, 10}) {
    for (const SeqSlamWindow w : {SeqSlamWindow::kCentred, SeqSlamWindow::kTrailing}) {
      SeqSlamParams p;
      p.sequence_length = ds;
      std::vector<SeqSlamMatch> whole(n_query);
      ASSERT_EQ(BatchSeqSlam(ref, query, route.dim, p, w, whole), SeqSlamError::kOk);
      int valid = 0;
      for (const SeqSlamMatch& m : whole)
        valid += m.valid ? 1 : 0;
      EXPECT_EQ(valid, n_query - ds + 1);
      for (const int block : {1, 3, 7, 32, 89, 90, 1000, std::numeric_limits<int>::max()}) {
        BlockedSeqSlamOptions o;
        o.block_columns = block;
        std::vector<SeqSlamMatch> blocked(n_query);
        ASSERT_EQ(BlockedBatchSeqSlam(DescriptorRows::Floats(ref, route.dim),
                                      DescriptorRows::Floats(query, route.dim), p, w, o, blocked),
                  SeqSlamError::kOk);
        ExpectSameMatches(blocked, whole, "blocked");
      }
    }
  }
}

// Work split as threads would split it (ranges in any order) changes nothing, and byte
// descriptors give SeqSlamFromDifferences over their integer differences.
TEST(SeqSlamBatchBlocked, RangesInAnyOrderAndBytesEqualTheReference) {
  testing::SyntheticRoute route;
  route.dim = 256;
  const int n_ref = 200, n_query = 70;
  const std::vector<float> ref = route.Reference(n_ref);
  const std::vector<float> query = route.Query(n_query, n_ref, 20.0, 0.9, 1.0f);
  std::vector<std::uint8_t> ref8(ref.size()), query8(query.size());
  QuantiseToBytes(ref, ref8);
  QuantiseToBytes(query, query8);
  const DescriptorRows r = DescriptorRows::Bytes(ref8, route.dim);
  const DescriptorRows q = DescriptorRows::Bytes(query8, route.dim);
  std::vector<float> d(static_cast<std::size_t>(n_ref * n_query));
  DifferenceTile(r, q, 0, n_ref, 0, n_query, d.data(), static_cast<std::size_t>(n_ref));
  SeqSlamParams p;
  std::vector<SeqSlamMatch> reference(n_query);
  ASSERT_EQ(SeqSlamFromDifferences(d, n_ref, n_query, p, SeqSlamWindow::kCentred, reference),
            SeqSlamError::kOk);
  BlockedSeqSlamOptions o;
  o.block_columns = 16;
  std::vector<SeqSlamMatch> split(n_query);
  BlockedSeqSlam engine;
  ASSERT_EQ(engine.Init(r, q, p, SeqSlamWindow::kCentred, o, split), SeqSlamError::kOk);
  std::vector<float> scratch(engine.ScratchFloats()), scores(engine.ScoreFloats());
  for (int b = 0; b < engine.block_count(); ++b) {
    engine.Begin(b);
    // Backwards, in ranges of 5 columns and 3 frames.
    for (int end = engine.ColumnCount(); end > 0; end -= 5)
      engine.ComputeColumns(std::max(0, end - 5), end, scratch);
    for (int end = engine.SearchCount(); end > 0; end -= 3)
      engine.Search(std::max(0, end - 3), end, scores);
  }
  ExpectSameMatches(split, reference, "ranges");
  int correct = 0;
  for (int t = 0; t < n_query; ++t) {
    const SeqSlamMatch& m = split[static_cast<std::size_t>(t)];
    correct += m.valid && std::abs(m.reference - static_cast<int>(20.0 + 0.9 * t)) <= 2 ? 1 : 0;
  }
  EXPECT_GE(correct, n_query - 12);  // and it finds the route (61 frames have a window)
  // Memory: the store holds block + ds - 1 columns, not the whole matrix.
  EXPECT_EQ(engine.AllocatedBytes(), sizeof(float) * static_cast<std::size_t>(n_ref) * (16 + 9));
}

TEST(SeqSlamBatchBlocked, RejectsMismatchedInputs) {
  const std::vector<float> f(20, 0.0f);
  const std::vector<std::uint8_t> b(20, 0);
  std::vector<SeqSlamMatch> m(2);
  const SeqSlamParams p;
  const BlockedSeqSlamOptions o;
  EXPECT_EQ(BlockedBatchSeqSlam(DescriptorRows::Floats(f, 10), DescriptorRows::Bytes(b, 10), p,
                                SeqSlamWindow::kCentred, o, m),
            SeqSlamError::kSizeMismatch);
  EXPECT_EQ(BlockedBatchSeqSlam(DescriptorRows::Floats(f, 10), DescriptorRows::Floats(f, 5), p,
                                SeqSlamWindow::kCentred, o, m),
            SeqSlamError::kBadDimension);
  std::vector<SeqSlamMatch> wrong(3);
  EXPECT_EQ(BlockedBatchSeqSlam(DescriptorRows::Floats(f, 10), DescriptorRows::Floats(f, 10), p,
                                SeqSlamWindow::kCentred, o, wrong),
            SeqSlamError::kSizeMismatch);
  // An empty route: runs, and nothing is valid (as BatchSeqSlam).
  EXPECT_EQ(BlockedBatchSeqSlam(DescriptorRows::Floats({}, 10), DescriptorRows::Floats(f, 10), p,
                                SeqSlamWindow::kCentred, o, m),
            SeqSlamError::kOk);
  EXPECT_FALSE(m[0].valid);
  // Fewer query frames than ds: runs, and nothing is valid.
  EXPECT_EQ(BlockedBatchSeqSlam(DescriptorRows::Floats(f, 10), DescriptorRows::Floats(f, 10), p,
                                SeqSlamWindow::kCentred, o, m),
            SeqSlamError::kOk);
  EXPECT_FALSE(m[0].valid);
  EXPECT_FALSE(m[1].valid);
}

}  // namespace
}  // namespace skyloc::dsp
