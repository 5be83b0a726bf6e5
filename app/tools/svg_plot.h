// The two plots `skyloc eval` and `skyloc experiment` draw, as SVG text: precision-recall
// curves of several runs, and frame correspondences (matched reference against query
// frame over the ground truth, the paper's Fig. 5a). Plain data in, the document out;
// the commands write it where they like.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "skyloc/dsp/place_metrics.h"

namespace skyloc::tools {

enum class LineDash : std::uint8_t { kSolid, kDashed, kDotted };

struct PrCurve {
  std::string name;                  // the legend text
  std::vector<dsp::PrPoint> points;  // as dsp::EvaluatePrecisionRecall gives them: rising recall
  LineDash dash = LineDash::kSolid;
};

// Precision (y) against recall (x), both 0..1, one step curve per entry of `curves` in the
// palette's colours, a legend line per curve below the plot.
std::string PrPlotSvg(std::string_view title, std::span<const PrCurve> curves);

struct RocCurveLine {
  std::string name;                   // the legend text
  std::vector<dsp::RocPoint> points;  // as dsp::RocCurve gives them: from (0, 0) to (1, 1)
  LineDash dash = LineDash::kSolid;
};

// True positive rate (y) against false positive rate (x), both 0..1, straight segments
// between the points (the trapezoids of dsp::RocArea), the chance diagonal in grey, a
// legend line per curve below the plot.
std::string RocPlotSvg(std::string_view title, std::span<const RocCurveLine> curves);

struct CorrespondenceMatch {
  int query = 0;      // query frame index
  int reference = 0;  // the matched reference frame index
  bool correct = false;
};

struct CorrespondencePanel {
  std::string name;               // titled "name (C of N correct)"
  std::vector<int> ground_truth;  // per query frame: the true reference frame, -1 off route
  int reference_frames = 0;       // the y axis spans frames 0..reference_frames - 1
  std::vector<CorrespondenceMatch> matches;
};

// One panel per entry, `columns` panels a row: x = query frame, y = reference frame,
// the ground truth a black line broken where the query is off the route, a green dot per
// correct match and a red dot per wrong one.
std::string CorrespondenceSvg(std::span<const CorrespondencePanel> panels, int columns);

}  // namespace skyloc::tools
