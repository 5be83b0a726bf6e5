#include "tools/experiment.h"

#include <gtest/gtest.h>

#include <string>

namespace skyloc::tools {
namespace {

// The paper's central claim on a short simulated City: at a 40 degree tilt difference
// between the runs, SeqSLAM on the sky shape (UV, SH amplitudes) recalls more at 100 %
// precision, and is more often right, than SeqSLAM on the images themselves.
TEST(Experiment, SkyBeatsVanillaAtFortyDegreesTiltDifference) {
  ExperimentOptions options;
  options.width = 80;
  options.height = 60;
  options.config.descriptor.bands = 16;
  options.config.descriptor.grid = firmware::GridPreset::kAuto;  // the paper's grid
  firmware::ResolveDescriptorGrid(&options.config.descriptor);
  options.frames.frame_spacing_m = 5.0;  // ~100 frames a lap
  options.max_offset_m = 6.0;
  const int differences[] = {0, 40};
  std::vector<TiltRow> rows;
  const Status s = RunTiltExperiment(options, differences, &rows);
  ASSERT_TRUE(s.ok()) << s.message();
  ASSERT_EQ(rows.size(), 2u);
  for (const TiltRow& row : rows) {
    std::printf(
        "tilt difference %2.0f: sky R@P100 %.3f P@R100 %.3f | vanilla R@P100 %.3f "
        "P@R100 %.3f\n",
        row.tilt_difference_deg, row.sky.summary.recall_at_full_precision,
        row.sky.summary.precision_at_full_recall, row.vanilla.summary.recall_at_full_precision,
        row.vanilla.summary.precision_at_full_recall);
  }
  const TiltRow& level = rows[0];
  const TiltRow& tilted = rows[1];
  EXPECT_EQ(tilted.reference_tilt_deg, 20);
  EXPECT_EQ(tilted.query_tilt_deg, -20);
  // Both methods work when the runs are level (the comparison is meaningful).
  EXPECT_GT(level.sky.summary.precision_at_full_recall, 0.5);
  EXPECT_GT(level.vanilla.summary.precision_at_full_recall, 0.5);
  // Tilted: sky wins.
  EXPECT_GT(tilted.sky.summary.precision_at_full_recall,
            tilted.vanilla.summary.precision_at_full_recall + 0.1);
  EXPECT_GE(tilted.sky.summary.recall_at_full_precision,
            tilted.vanilla.summary.recall_at_full_precision);
}

// FAB-MAP needs the runs' words: runs described without a vocabulary are refused by name,
// not scored as if every frame had seen nothing.
TEST(Experiment, FabmapWithoutWordsIsAnError) {
  RunDescriptors run;
  run.trajectory.resize(3);
  ExperimentOptions options;
  MethodScore score;
  const Status s = ScoreRuns(run, run, ScoredDescriptor::kFabmap, firmware::Matcher::kOpenSeqSlam,
                             options, &score);
  EXPECT_EQ(s.code(), StatusCode::kFailedPrecondition);
  EXPECT_NE(std::string(s.message()).find("FAB-MAP"), std::string::npos) << s.message();
}

}  // namespace
}  // namespace skyloc::tools
