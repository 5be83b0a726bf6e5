#include "tools/eval_score.h"

#include <gtest/gtest.h>

#include <cstdio>
#include <random>
#include <string>
#include <vector>

#include "support/scratch_dir.h"
#include "tools/eval_match.h"

namespace skyloc::tools {
namespace {

Result<GroundTruth> ReadCsv(const std::string& text, int n_query, int n_ref) {
  const skyloc::testing::ScratchDir dir("eval_score_");
  const std::string path = dir.path() + "/gt.csv";
  std::FILE* f = std::fopen(path.c_str(), "wb");
  EXPECT_NE(f, nullptr);
  std::fputs(text.c_str(), f);
  std::fclose(f);
  return ReadGroundTruthCsv(path, n_query, n_ref, dsp::MatchTolerance{});
}

TEST(EvalScore, GroundTruthFileGivesOneFramePerListedQuery) {
  const Result<GroundTruth> gt = ReadCsv("query_index,reference_index\n0,2\n1,-1\n\n3,5\n", 4, 6);
  ASSERT_TRUE(gt.ok()) << gt.status().message();
  ASSERT_EQ(gt->truth.size(), 4u);
  EXPECT_EQ(gt->truth[0].first, 2);
  EXPECT_EQ(gt->truth[0].last, 2);
  EXPECT_FALSE(gt->truth[1].has_truth());  // -1: off the route
  EXPECT_FALSE(gt->truth[2].has_truth());  // not listed
  EXPECT_EQ(gt->truth[3].nearest, 5);
  EXPECT_NE(gt->description.find("gt.csv"), std::string::npos);
}

TEST(EvalScore, GroundTruthFileRefusesBadLines) {
  const struct {
    std::string text;
    std::string message;
  } cases[] = {
      {"query,reference\n0,1\n", "header must be"},
      {"query_index,reference_index\n0,1\n0,2\n", ":3: query_index 0 given twice"},
      {"query_index,reference_index\n4,1\n", "query_index 4 outside the query run's 0..3"},
      {"query_index,reference_index\n0,6\n", "reference_index 6 outside -1..5"},
      {"query_index,reference_index\n0;1\n", "expected two integers"},
      {"", "empty file"},
  };
  for (const auto& c : cases) {
    const Result<GroundTruth> gt = ReadCsv(c.text, 4, 6);
    ASSERT_FALSE(gt.ok()) << c.text;
    EXPECT_EQ(gt.status().code(), StatusCode::kInvalidArgument) << c.text;
    EXPECT_NE(std::string(gt.status().message()).find(c.message), std::string::npos)
        << gt.status().message();
  }
}

dsp::SeqSlamMatch Match(int reference, float uniqueness) {
  dsp::SeqSlamMatch m;
  m.valid = true;
  m.reference = reference;
  m.uniqueness = uniqueness;
  return m;
}

// Reference frames 1 m apart along x; queries on frames 0..4 and one 100 m away (off
// the route: farther than 3 m). Tolerance +-1 frame. Worked by hand:
//   q0 -> 0, u 0.1: right | q1 -> 5, u 0.2: wrong | q2: no match (not evaluated)
//   q3 -> 4, u 0.3: right (one frame off) | q4: no match | q5 -> 9, u 0.4: off the route
// evaluated 4, with truth 3, correct 2; everything accepted: precision 2 / 4.
TEST(EvalScore, ScoresOnlyMatchedQueriesAgainstThePositions) {
  std::vector<dsp::Position3> reference, query;
  for (int i = 0; i < 10; ++i)
    reference.push_back({static_cast<double>(i), 0, 0});
  for (int i = 0; i < 5; ++i)
    query.push_back({static_cast<double>(i), 0.2, 0});
  query.push_back({100, 0, 0});
  const GroundTruth gt =
      GroundTruthFromPositions(reference, query, 3.0, dsp::MatchTolerance{1, 0, 0});
  std::vector<dsp::SeqSlamMatch> matches(6);
  matches[0] = Match(0, 0.1f);
  matches[1] = Match(5, 0.2f);
  matches[3] = Match(4, 0.3f);
  matches[5] = Match(9, 0.4f);
  const ScoredMatches s = ScoreMatches(gt, matches);
  EXPECT_EQ(s.evaluated_queries, (std::vector<int>{0, 1, 3, 5}));
  ASSERT_EQ(s.evaluated.size(), 4u);
  EXPECT_TRUE(s.evaluated[0].correct);
  EXPECT_FALSE(s.evaluated[1].correct);
  EXPECT_TRUE(s.evaluated[2].correct);
  EXPECT_FALSE(s.evaluated[3].has_ground_truth);
  EXPECT_EQ(s.pr.summary.evaluated, 4);
  EXPECT_EQ(s.pr.summary.with_ground_truth, 3);
  EXPECT_EQ(s.pr.summary.correct, 2);
  EXPECT_DOUBLE_EQ(s.pr.summary.precision_at_full_recall, 0.5);
  EXPECT_DOUBLE_EQ(s.pr.summary.recall_at_full_precision, 1.0 / 3);  // q0 alone
  ASSERT_EQ(s.pr.curve.size(), 4u);
  // LOCALISED on q1 and q3 (q2 has no match: not counted even when LOCALISED).
  std::vector<dsp::LocalisationState> states(6, dsp::LocalisationState::kSearching);
  states[1] = states[2] = states[3] = dsp::LocalisationState::kLocalised;
  const LocalisedCount c = CountLocalised(states, s);
  EXPECT_EQ(c.localised, 2);
  EXPECT_EQ(c.correct, 1);
}

TEST(EvalMatch, DescriptorNamesRoundTrip) {
  for (const ScoredDescriptor d :
       {ScoredDescriptor::kSky, ScoredDescriptor::kSkyCap, ScoredDescriptor::kVanilla,
        ScoredDescriptor::kFabmap, ScoredDescriptor::kSurf1d}) {
    ScoredDescriptor parsed = ScoredDescriptor::kSurf1d;
    ASSERT_TRUE(ParseScoredDescriptor(ScoredDescriptorName(d), &parsed)) << ScoredDescriptorName(d);
    EXPECT_EQ(parsed, d);
  }
  ScoredDescriptor unused;
  EXPECT_FALSE(ParseScoredDescriptor("sky cap", &unused));
  EXPECT_STREQ(ScoredDescriptorName(ScoredDescriptor::kSkyCap), "sky_cap");
}

// The batch engine is the blocked one on any number of threads: the same matches, bit
// for bit, as dsp::BatchSeqSlam over the whole difference matrix (what the experiments
// used before they matched through MatchRows).
TEST(EvalMatch, BatchMatchesAreTheWholeMatrixEngines) {
  constexpr int kFrames = 60, kDim = 16;
  std::mt19937 rng(7);
  std::normal_distribution<float> noise;
  std::vector<float> reference(kFrames * kDim), query(kFrames * kDim);
  for (std::size_t i = 0; i < reference.size(); ++i) {
    reference[i] = noise(rng);
    query[i] = reference[i] + 0.5f * noise(rng);
  }
  dsp::SeqSlamParams params;
  params.sequence_length = 5;
  std::vector<dsp::SeqSlamMatch> expected(kFrames);
  ASSERT_EQ(
      dsp::BatchSeqSlam(reference, query, kDim, params, dsp::SeqSlamWindow::kCentred, expected),
      dsp::SeqSlamError::kOk);
  int valid = 0;
  for (const int jobs : {1, 3}) {
    MatcherSettings settings;
    settings.matcher = firmware::Matcher::kOpenSeqSlam;
    settings.openseqslam = params;
    settings.jobs = jobs;
    std::vector<dsp::SeqSlamMatch> matches(kFrames);
    ASSERT_TRUE(
        MatchRows({kDim, kFrames, reference, {}}, {kDim, kFrames, query, {}}, settings, matches)
            .ok());
    for (std::size_t q = 0; q < matches.size(); ++q) {
      EXPECT_EQ(matches[q].valid, expected[q].valid) << q;
      EXPECT_EQ(matches[q].reference, expected[q].reference) << q;
      EXPECT_EQ(matches[q].uniqueness, expected[q].uniqueness) << q;
      valid += matches[q].valid ? 1 : 0;
    }
  }
  EXPECT_GT(valid, kFrames);  // most frames of both runs have a match to compare
  std::vector<dsp::SeqSlamMatch> too_few(kFrames - 1);
  EXPECT_EQ(MatchRows({kDim, kFrames, reference, {}}, {kDim, kFrames, query, {}}, MatcherSettings{},
                      too_few)
                .code(),
            StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace skyloc::tools
