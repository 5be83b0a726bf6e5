#include "tools/eval_results.h"

#include <cstdio>

#include "tools/output_file.h"
#include "tools/svg_plot.h"

namespace skyloc::tools {

std::string JsonString(const std::string& s) {
  std::string out = "\"";
  for (const char c : s) {
    if (c == '"' || c == '\\') {
      out += '\\';
      out += c;
    } else if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", static_cast<unsigned>(c));
      out += buf;
    } else {
      out += c;
    }
  }
  return out + "\"";
}

std::string ScoreFieldsJson(const dsp::PrSummary& s, std::span<const dsp::PrPoint> curve) {
  std::string json = Format(
      "\"evaluated\": %d, \"with_ground_truth\": %d, \"correct\": %d, "
      "\"precision_at_100_recall\": %.6f, \"recall_at_100_precision\": %.6f, \"auc\": %.6f, "
      "\"curve\": [",
      s.evaluated, s.with_ground_truth, s.correct, s.precision_at_full_recall,
      s.recall_at_full_precision, s.area_under_curve);
  for (std::size_t k = 0; k < curve.size(); ++k) {
    const dsp::PrPoint& p = curve[k];
    json += Format("%s{\"threshold\": %.6g, \"precision\": %.6f, \"recall\": %.6f}",
                   k == 0 ? "" : ", ", static_cast<double>(p.threshold), p.precision, p.recall);
  }
  return json + "]";
}

std::string HeadingSummaryJson(const dsp::HeadingErrorSummary& h) {
  return Format(
      "{\"frames\": %d, \"estimated\": %d, \"median_deg\": %.6f, \"p90_deg\": %.6f, "
      "\"max_deg\": %.6f}",
      h.frames, h.estimated, h.median_deg, h.p90_deg, h.max_deg);
}

std::string MetricsJsonHead(const char* tool) {
  return "{\n  \"schema\": " + JsonString(kMetricsSchema) + ",\n  \"tool\": " + JsonString(tool) +
         ",\n";
}

Status WriteMatchesCsv(const std::string& path, const std::vector<EvalRun>& runs) {
  OutFile f;
  SKYLOC_TRY(f.Open(path));
  // New columns go last, so readers of the first seven keep working.
  std::fprintf(f.get(),
               "method,ds,query_index,reference_index,score,uniqueness,correct,matcher,state\n");
  for (const EvalRun& run : runs) {
    for (std::size_t i = 0; i < run.scored.evaluated_queries.size(); ++i) {
      const int q = run.scored.evaluated_queries[i];
      const dsp::SeqSlamMatch& m = run.matches[static_cast<std::size_t>(q)];
      std::fprintf(f.get(), "%s,%d,%d,%d,%.6g,%.6g,%d,%s,%s\n",
                   ScoredDescriptorName(run.descriptor), run.ds, q, m.reference,
                   static_cast<double>(m.score), static_cast<double>(m.uniqueness),
                   run.scored.evaluated[i].correct ? 1 : 0, run.matcher_name.c_str(),
                   dsp::LocalisationStateName(run.states[static_cast<std::size_t>(q)]));
    }
  }
  return f.Close();
}

Status WriteEvalMetricsJson(const std::string& path, const EvalMetricsHeader& h,
                            const std::vector<EvalRun>& runs) {
  std::string json = MetricsJsonHead("eval");
  json += "  \"reference\": " + JsonString(h.reference) + ",\n  \"query\": " + JsonString(h.query) +
          ",\n";
  json += Format("  \"reference_frames\": %d,\n  \"query_frames\": %d,\n", h.reference_frames,
                 h.query_frames);
  json += "  \"openseqslam_engine\": " +
          JsonString(h.streaming ? "streaming (trailing window)" : "batch (centred window)") +
          ",\n  \"vanilla_precision_batch\": " + JsonString(h.vanilla_bytes ? "byte" : "float") +
          ",\n  \"ground_truth\": " + JsonString(h.ground_truth) +
          Format(",\n  \"frame_tolerance\": %d,\n  \"runs\": [\n", h.frame_tolerance);
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const EvalRun& r = runs[i];
    json += "    {\"method\": " + JsonString(ScoredDescriptorName(r.descriptor)) +
            ", \"matcher\": " + JsonString(r.matcher_name) + Format(", \"ds\": %d,\n     ", r.ds);
    json += ScoreFieldsJson(r.scored.pr.summary, r.scored.pr.curve);
    json += Format(",\n     \"localised\": %d, \"localised_correct\": %d,\n", r.localised.localised,
                   r.localised.correct);
    json +=
        r.heading_evaluated
            ? "     \"heading\": {\"correlation\": " + HeadingSummaryJson(r.heading.correlation) +
                  ", \"surf\": " + HeadingSummaryJson(r.heading.surf) + "}"
            : std::string("     \"heading\": null");
    json += std::string("}") + (i + 1 < runs.size() ? ",\n" : "\n");
  }
  json += "  ]\n}\n";
  return WriteText(path, json);
}

std::string EvalPrPlot(const std::vector<EvalRun>& runs) {
  std::vector<PrCurve> curves;
  for (const EvalRun& r : runs) {
    const dsp::PrSummary& s = r.scored.pr.summary;
    const std::string summary =
        Format(": AUC %.3f, precision at 100%% recall %.3f, recall at 100%% precision %.3f",
               s.area_under_curve, s.precision_at_full_recall, s.recall_at_full_precision);
    // Dashed ds = 1 and dotted ds >= 20 tell the sequence lengths of one method apart
    // (docs/SEQSLAM.md).
    const LineDash dash =
        r.ds == 1 ? LineDash::kDashed : (r.ds >= 20 ? LineDash::kDotted : LineDash::kSolid);
    curves.push_back({r.label() + summary, r.scored.pr.curve, dash});
  }
  return PrPlotSvg("Precision - recall (sweeping the uniqueness threshold)", curves);
}

std::string EvalCorrespondencePlot(const std::vector<EvalRun>& runs, const GroundTruth& truth,
                                   int n_ref) {
  std::vector<int> nearest;  // the truth line: the nearest reference frame of each query
  for (const dsp::TruthInterval& t : truth.truth)
    nearest.push_back(t.nearest);
  std::vector<CorrespondencePanel> panels;
  for (const EvalRun& r : runs) {
    CorrespondencePanel panel{r.label(), nearest, n_ref, {}};
    for (std::size_t k = 0; k < r.scored.evaluated_queries.size(); ++k) {
      const int q = r.scored.evaluated_queries[k];
      panel.matches.push_back(
          {q, r.matches[static_cast<std::size_t>(q)].reference, r.scored.evaluated[k].correct});
    }
    panels.push_back(std::move(panel));
  }
  return CorrespondenceSvg(panels, 3);
}

}  // namespace skyloc::tools
