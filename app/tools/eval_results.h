// The result files of `skyloc eval` and the experiments: matches.csv, metrics.json (one
// schema, docs/METRICS.md), pr.svg and correspondence.svg.
#pragma once

#include <span>
#include <string>
#include <vector>

#include "skyloc/dsp/place_metrics.h"
#include "skyloc/platform/status.h"
#include "tools/eval_score.h"

namespace skyloc::tools {

// The "schema" field of every metrics.json; a reader checks it before the other fields.
inline constexpr const char* kMetricsSchema = "skyloc-metrics/1";

// A JSON string literal of `s` (quotes, backslashes and control characters escaped).
std::string JsonString(const std::string& s);

// The precision-recall fields of one scored run, the same in every metrics.json (without
// the braces): evaluated, with_ground_truth, correct, precision_at_100_recall,
// recall_at_100_precision, auc, curve. Reals with six decimals; a curve point's threshold
// with six significant digits (a uniqueness ratio can be far below 1e-6).
std::string ScoreFieldsJson(const dsp::PrSummary& summary, std::span<const dsp::PrPoint> curve);

// {"frames", "estimated", "median_deg", "p90_deg", "max_deg"}.
std::string HeadingSummaryJson(const dsp::HeadingErrorSummary& summary);

// The first fields of every metrics.json: {"schema": ..., "tool": TOOL, then a newline.
std::string MetricsJsonHead(const char* tool);

// method,ds,query_index,reference_index,score,uniqueness,correct,matcher,state: one line
// per evaluated query frame of every run.
Status WriteMatchesCsv(const std::string& path, const std::vector<EvalRun>& runs);

// What `skyloc eval`'s metrics.json says about the evaluation as a whole.
struct EvalMetricsHeader {
  std::string reference, query;  // the dataset folders
  int reference_frames = 0, query_frames = 0;
  bool streaming = false;      // OpenSeqSLAM's engine: streaming or batch
  bool vanilla_bytes = false;  // the batch engine's vanilla descriptor in bytes
  std::string ground_truth;    // GroundTruth::description
  int frame_tolerance = 0;
};

Status WriteEvalMetricsJson(const std::string& path, const EvalMetricsHeader& header,
                            const std::vector<EvalRun>& runs);

// One curve per run, its summary in the legend.
std::string EvalPrPlot(const std::vector<EvalRun>& runs);
// One panel per run, at most three a row.
std::string EvalCorrespondencePlot(const std::vector<EvalRun>& runs, const GroundTruth& truth,
                                   int n_ref);

}  // namespace skyloc::tools
