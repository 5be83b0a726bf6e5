// skyloc eval's threads (app/src/parallel.h) and progress line (app/src/progress.h): the
// blocked batch SeqSLAM on several threads and block sizes gives the unblocked
// one-thread engine's matches bit for bit.
#include "tools/parallel.h"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <string>
#include <vector>

#include "support/synthetic_descriptors.h"
#include "tools/progress.h"

namespace skyloc::tools {
namespace {

TEST(ParallelFor, RunsEveryTaskOnceWithWorkerIndicesInRange) {
  for (const int jobs : {1, 2, 3, 8}) {
    std::vector<std::atomic<int>> runs(100);
    std::atomic<int> bad_worker{0};
    ParallelFor(jobs, 100, [&](int task, int worker) {
      runs[static_cast<std::size_t>(task)].fetch_add(1);
      if (worker < 0 || worker >= jobs)
        bad_worker.fetch_add(1);
    });
    for (const auto& r : runs)
      EXPECT_EQ(r.load(), 1) << "jobs " << jobs;
    EXPECT_EQ(bad_worker.load(), 0);
  }
  ParallelFor(4, 0, [](int, int) { ADD_FAILURE() << "no tasks, no calls"; });
}

void ExpectSame(const std::vector<dsp::SeqSlamMatch>& a, const std::vector<dsp::SeqSlamMatch>& b,
                int block, int jobs) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t t = 0; t < a.size(); ++t) {
    ASSERT_EQ(a[t].valid, b[t].valid) << "block " << block << " jobs " << jobs << " t " << t;
    if (!a[t].valid)
      continue;
    EXPECT_EQ(a[t].reference, b[t].reference)
        << "block " << block << " jobs " << jobs << " t " << t;
    EXPECT_EQ(a[t].start, b[t].start);
    EXPECT_EQ(a[t].velocity, b[t].velocity);
    EXPECT_EQ(a[t].score, b[t].score) << "block " << block << " jobs " << jobs << " t " << t;
    EXPECT_EQ(a[t].uniqueness, b[t].uniqueness);
    EXPECT_EQ(a[t].confidence, b[t].confidence);
  }
}

// Block size and thread count do not change a bit of the
// result, for float and for byte descriptors.
TEST(BlockedSeqSlamThreads, BitIdenticalToTheUnblockedOneThreadEngine) {
  testing::SyntheticRoute route;
  // 512 values (a quarter of the vanilla descriptor's, so the 32 runs stay quick under
  // qemu on the ARM builds); the kernels' tails are covered by tests/dsp.
  route.dim = 512;
  const int n_ref = 200, n_query = 100;
  const std::vector<float> ref = route.Reference(n_ref);
  const std::vector<float> query = route.Query(n_query, n_ref, 30.0, 1.15, 2.0f);
  std::vector<std::uint8_t> ref8(ref.size()), query8(query.size());
  dsp::QuantiseToBytes(ref, ref8);
  dsp::QuantiseToBytes(query, query8);
  dsp::SeqSlamParams p;  // ds 10, v 0.8-1.2, R 10
  for (const bool bytes : {false, true}) {
    const dsp::DescriptorRows r = bytes ? dsp::DescriptorRows::Bytes(ref8, route.dim)
                                        : dsp::DescriptorRows::Floats(ref, route.dim);
    const dsp::DescriptorRows q = bytes ? dsp::DescriptorRows::Bytes(query8, route.dim)
                                        : dsp::DescriptorRows::Floats(query, route.dim);
    // The reference: the whole matrix at once, one thread, no blocking.
    std::vector<dsp::SeqSlamMatch> whole(n_query);
    if (bytes) {
      std::vector<float> d(static_cast<std::size_t>(n_ref * n_query));
      dsp::DifferenceTile(r, q, 0, n_ref, 0, n_query, d.data(), static_cast<std::size_t>(n_ref));
      ASSERT_EQ(
          dsp::SeqSlamFromDifferences(d, n_ref, n_query, p, dsp::SeqSlamWindow::kCentred, whole),
          dsp::SeqSlamError::kOk);
    } else {
      ASSERT_EQ(dsp::BatchSeqSlam(ref, query, route.dim, p, dsp::SeqSlamWindow::kCentred, whole),
                dsp::SeqSlamError::kOk);
    }
    int correct = 0;
    for (int t = 0; t < n_query; ++t) {
      const dsp::SeqSlamMatch& m = whole[static_cast<std::size_t>(t)];
      correct += m.valid && std::abs(m.reference - static_cast<int>(30.0 + 1.15 * t)) <= 2;
    }
    EXPECT_GE(correct, n_query - 12) << "bytes " << bytes;  // a route that is found
    for (const int block : {1, 5, 64, 400}) {
      for (const int jobs : {1, 2, 3, 7}) {
        dsp::BlockedSeqSlamOptions o;
        o.block_columns = block;
        std::vector<dsp::SeqSlamMatch> got(n_query);
        dsp::BlockedSeqSlam engine;
        ASSERT_EQ(engine.Init(r, q, p, dsp::SeqSlamWindow::kCentred, o, got),
                  dsp::SeqSlamError::kOk);
        int last_progress = 0;
        RunBlockedSeqSlam(engine, jobs, [&](int done) { last_progress = done; });
        EXPECT_EQ(last_progress, n_query);
        ExpectSame(got, whole, block, jobs);
      }
    }
  }
}

std::string Written(std::FILE* f) {
  std::rewind(f);
  std::string s;
  char buf[256];
  while (std::fgets(buf, sizeof buf, f) != nullptr)
    s += buf;
  return s;
}

TEST(Progress, QuietWhenNotATerminalAndShort) {
  std::FILE* f = std::tmpfile();  // removed by the C library when closed
  ASSERT_NE(f, nullptr);
  {
    Progress p("vanilla descriptors", "frames", 1000, /*tty=*/0, f);
    for (long i = 1; i <= 1000; ++i)
      p.Update(i);
    p.Finish();
  }
  EXPECT_EQ(Written(f), "");
  std::fclose(f);
}

TEST(Progress, TerminalGetsOneRewrittenLineAndAFinalOne) {
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  {
    Progress p("matching", "query frames matched", 10, /*tty=*/1, f);
    p.Update(3);  // within the first quarter second: not written
    p.Finish();
  }
  const std::string s = Written(f);
  EXPECT_EQ(s.find("\r\033[Kskyloc eval: matching: 10 / 10 query frames matched (100 %), done in"),
            0u)
      << s;
  EXPECT_EQ(s.back(), '\n');
  std::fclose(f);
}

}  // namespace
}  // namespace skyloc::tools
