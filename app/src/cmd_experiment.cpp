// `skyloc experiment NAME --out DIR`: the paper's experiments on simulated runs (issue 5,
// docs/RESULTS.md). Each writes DIR/results.md (a markdown table and the command that
// made it), DIR/metrics.json, precision-recall plots DIR/pr_sky.svg and DIR/pr_vanilla.svg,
// and frame correspondences DIR/correspondence.svg.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "commands.h"
#include "skyloc/sim/experiment.h"

namespace skyloc::app {
namespace {

constexpr const char* kUsage =
    "usage: skyloc experiment tilt|manoeuvre|ants --out DIR [options]\n"
    "\n"
    "  tilt       City loop, runs at tilt -30..30 paired alpha1 ~ -alpha2 (differences\n"
    "             0..60): recall at 100 % precision, sky vs vanilla SeqSLAM\n"
    "  manoeuvre  forest (BMX) and repetitive (Disposal) worlds, reference at noon vs a\n"
    "             dawn run with zig-zag and bumps: precision at 100 % recall, ds 1/10/20\n"
    "  ants       Seville habitat, ant1_route1 as reference vs other routes of ant 1 and\n"
    "             of other ants, at ant height (0.01 m) and robot height (0.1 m)\n"
    "\n"
    "options:\n"
    "  --width W --height H   image size (default 320x240)\n"
    "  --bands N              SH bands of the sky descriptor (default 120, as the paper)\n"
    "  --spacing M            frame spacing in metres (default 1; ants 0.05)\n"
    "  --frames N             at most N frames a run (default: whole routes)\n"
    "  --seed N               procedural world seed (default 1)\n"
    "  --data DIR             Seville data folder (default ../shared/data/seville2009)\n";

struct Options {
  std::string name, out, data_dir = "../shared/data/seville2009";
  sim::ExperimentOptions experiment;
  bool spacing_given = false;
};

bool ParseNumber(const char* text, double lo, double hi, double* value) {
  char* end = nullptr;
  *value = std::strtod(text, &end);
  return end != text && *end == '\0' && *value >= lo && *value <= hi;
}

int ParseArgs(std::span<char* const> args, Options* o) {
  if (args.empty() || args[0][0] == '-') {
    std::fprintf(stderr, "skyloc experiment: name the experiment: tilt, manoeuvre or ants\n");
    return kExitUsage;
  }
  o->name = args[0];
  if (o->name != "tilt" && o->name != "manoeuvre" && o->name != "ants") {
    std::fprintf(stderr, "skyloc experiment: unknown experiment '%s' (tilt, manoeuvre, ants)\n",
                 args[0]);
    return kExitUsage;
  }
  for (std::size_t i = 1; i < args.size(); ++i) {
    const char* flag = args[i];
    if (i + 1 >= args.size()) {
      std::fprintf(stderr, "skyloc experiment: %s needs a value (see --help)\n", flag);
      return kExitUsage;
    }
    const char* v = args[++i];
    double d = 0;
    auto bad = [&](const char* expected) {
      std::fprintf(stderr, "skyloc experiment: %s '%s': expected %s\n", flag, v, expected);
      return kExitUsage;
    };
    sim::ExperimentOptions& e = o->experiment;
    if (std::strcmp(flag, "--out") == 0) {
      o->out = v;
    } else if (std::strcmp(flag, "--data") == 0) {
      o->data_dir = v;
    } else if (std::strcmp(flag, "--width") == 0) {
      if (!ParseNumber(v, 16, 4096, &d) || d != std::floor(d))
        return bad("pixels within 16..4096");
      e.width = static_cast<int>(d);
    } else if (std::strcmp(flag, "--height") == 0) {
      if (!ParseNumber(v, 16, 4096, &d) || d != std::floor(d))
        return bad("pixels within 16..4096");
      e.height = static_cast<int>(d);
    } else if (std::strcmp(flag, "--bands") == 0) {
      if (!ParseNumber(v, 2, 200, &d) || d != std::floor(d))
        return bad("an integer within 2..200");
      e.bands = static_cast<int>(d);
    } else if (std::strcmp(flag, "--spacing") == 0) {
      if (!ParseNumber(v, 0.001, 100, &d))
        return bad("metres within 0.001..100");
      e.spacing_m = d;
      o->spacing_given = true;
    } else if (std::strcmp(flag, "--frames") == 0) {
      if (!ParseNumber(v, 20, 1e6, &d) || d != std::floor(d))
        return bad("an integer of at least 20");
      e.max_frames = static_cast<int>(d);
    } else if (std::strcmp(flag, "--seed") == 0) {
      if (!ParseNumber(v, 0, 1e15, &d) || d != std::floor(d))
        return bad("a non-negative integer");
      e.world_seed = static_cast<std::uint64_t>(d);
    } else {
      std::fprintf(stderr, "skyloc experiment: unknown option '%s' (see --help)\n", flag);
      return kExitUsage;
    }
  }
  if (o->out.empty()) {
    std::fprintf(stderr, "skyloc experiment: --out DIR is required\n");
    return kExitUsage;
  }
  return kExitOk;
}

// A row of any experiment, as the writers see it.
struct Row {
  std::string label;    // also the plot legend
  std::string columns;  // markdown cells before the metrics
  std::string json;     // JSON fields before the metrics
  const sim::MethodScore* sky;
  const sim::MethodScore* vanilla;
};

// printf into a std::string; for short pieces (at most 511 characters).
std::string Format(const char* format, ...) __attribute__((format(printf, 1, 2)));
std::string Format(const char* format, ...) {
  char buffer[512];
  va_list args;
  va_start(args, format);
  std::vsnprintf(buffer, sizeof buffer, format, args);
  va_end(args);
  return buffer;
}

std::string SummaryJson(const sim::MethodScore& m) {
  std::string s = Format(
      "{\"evaluated\": %d, \"with_ground_truth\": %d, \"correct\": %d, "
      "\"precision_at_100_recall\": %.4f, \"recall_at_100_precision\": %.4f, \"auc\": %.4f, "
      "\"curve\": [",
      m.summary.evaluated, m.summary.with_ground_truth, m.summary.correct,
      m.summary.precision_at_full_recall, m.summary.recall_at_full_precision,
      m.summary.area_under_curve);
  for (std::size_t i = 0; i < m.curve.size(); ++i)
    s += Format("%s[%.4f, %.4f]", i ? ", " : "", m.curve[i].recall, m.curve[i].precision);
  return s + "]}";
}

Status WriteFile(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr)
    return Status::FromErrno(errno, "cannot write '%s'", path.c_str());
  std::fwrite(text.data(), 1, text.size(), f);
  const bool failed = std::ferror(f) != 0;
  if (std::fclose(f) != 0 || failed)
    return Status::FromErrno(errno, "cannot write '%s'", path.c_str());
  return Status::Ok();
}

// Precision-recall curves of one method, one polyline per row.
std::string PrPlotSvg(const char* title, const std::vector<Row>& rows, bool sky) {
  static constexpr const char* kColours[] = {"#1f77b4", "#ff7f0e", "#2ca02c", "#d62728", "#9467bd",
                                             "#8c564b", "#e377c2", "#7f7f7f", "#bcbd22", "#17becf"};
  constexpr double kX0 = 60, kY0 = 30, kW = 360, kH = 300;
  std::string s = Format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"640\" height=\"380\" "
      "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"640\" height=\"380\" "
      "fill=\"white\"/>\n<text x=\"%g\" y=\"18\" font-size=\"14\">%s</text>\n"
      "<rect x=\"%g\" y=\"%g\" width=\"%g\" height=\"%g\" fill=\"none\" stroke=\"black\"/>\n",
      kX0, title, kX0, kY0, kW, kH);
  for (int t = 0; t <= 10; t += 2) {
    const double f = t / 10.0;
    s += Format("<text x=\"%g\" y=\"%g\" text-anchor=\"middle\">%.1f</text>\n", kX0 + f * kW,
                kY0 + kH + 16, f);
    s += Format("<text x=\"%g\" y=\"%g\" text-anchor=\"end\">%.1f</text>\n", kX0 - 6,
                kY0 + kH - f * kH + 4, f);
  }
  s += Format("<text x=\"%g\" y=\"%g\" text-anchor=\"middle\">recall</text>\n", kX0 + kW / 2,
              kY0 + kH + 32);
  s += Format(
      "<text x=\"16\" y=\"%g\" transform=\"rotate(-90 16 %g)\" "
      "text-anchor=\"middle\">precision</text>\n",
      kY0 + kH / 2, kY0 + kH / 2);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const sim::MethodScore& m = sky ? *rows[i].sky : *rows[i].vanilla;
    const char* colour = kColours[i % 10];
    s += Format("<polyline fill=\"none\" stroke=\"%s\" stroke-width=\"1.5\" points=\"", colour);
    for (const dsp::PrPoint& p : m.curve)
      s += Format("%.1f,%.1f ", kX0 + p.recall * kW, kY0 + kH - p.precision * kH);
    s += "\"/>\n";
    s += Format("<text x=\"%g\" y=\"%g\" fill=\"%s\">%s</text>\n", kX0 + kW + 12,
                kY0 + 14 + 16.0 * static_cast<double>(i), colour, rows[i].label.c_str());
  }
  return s + "</svg>\n";
}

// Frame correspondences (the paper's Figs. 5a, 8, 9): for every row, vanilla (left) and
// sky (right); x = query frame, y = matched reference frame; grey = ground truth, green =
// correct match, red = wrong.
std::string CorrespondenceSvg(const std::vector<Row>& rows, int tolerance_frames) {
  constexpr double kW = 220, kH = 160, kPad = 40;
  const double width = 2 * (kW + kPad) + kPad;
  const double height = static_cast<double>(rows.size()) * (kH + kPad) + kPad;
  std::string s = Format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"%.0f\" "
      "font-family=\"sans-serif\" font-size=\"11\">\n<rect width=\"%.0f\" height=\"%.0f\" "
      "fill=\"white\"/>\n",
      width, height, width, height);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    for (int column = 0; column < 2; ++column) {
      const sim::MethodScore& m = column == 0 ? *rows[i].vanilla : *rows[i].sky;
      const double x0 = kPad + column * (kW + kPad);
      const double y0 = kPad / 2 + static_cast<double>(i) * (kH + kPad) + 12;
      const std::size_t n_query = m.truth.size();
      int n_ref = 1;
      for (std::size_t q = 0; q < n_query; ++q)
        n_ref = std::max({n_ref, m.truth[q] + 1, m.matched[q] + 1});
      s += Format("<text x=\"%g\" y=\"%g\">%s: %s</text>\n", x0, y0 - 4,
                  column == 0 ? "vanilla" : "sky", rows[i].label.c_str());
      s += Format(
          "<rect x=\"%g\" y=\"%g\" width=\"%g\" height=\"%g\" fill=\"none\" "
          "stroke=\"black\"/>\n",
          x0, y0, kW, kH);
      auto px = [&](std::size_t q) {
        return x0 +
               kW * static_cast<double>(q) / static_cast<double>(std::max<std::size_t>(n_query, 1));
      };
      auto py = [&](int r) { return y0 + kH - kH * r / n_ref; };
      // One path per colour, each point a zero-length segment with a round cap: a few
      // bytes a point, so the plot of a whole experiment stays small.
      std::string truth, correct, wrong;
      for (std::size_t q = 0; q < n_query; ++q) {
        if (m.truth[q] >= 0)
          truth += Format("M%.1f %.1fh0", px(q), py(m.truth[q]));
        if (m.matched[q] >= 0) {
          const bool ok = dsp::MatchWithinFrames(m.matched[q], m.truth[q], tolerance_frames);
          (ok ? correct : wrong) += Format("M%.1f %.1fh0", px(q), py(m.matched[q]));
        }
      }
      s += "<path d=\"" + truth +
           "\" stroke=\"#bbbbbb\" stroke-width=\"1.6\" stroke-linecap=\"round\"/>\n";
      s += "<path d=\"" + correct +
           "\" stroke=\"#2ca02c\" stroke-width=\"2.6\" stroke-linecap=\"round\"/>\n";
      s += "<path d=\"" + wrong +
           "\" stroke=\"#d62728\" stroke-width=\"2.6\" stroke-linecap=\"round\"/>\n";
      s += "\n";
    }
  }
  return s + "</svg>\n";
}

Status WriteOutputs(const Options& o, const std::string& command, const std::string& header,
                    const std::string& separator, const std::vector<Row>& rows,
                    const std::string& notes) {
  if (::mkdir(o.out.c_str(), 0755) != 0 && errno != EEXIST)
    return Status::FromErrno(errno, "cannot create '%s'", o.out.c_str());
  std::string md = "# skyloc experiment " + o.name + "\n\n```\n" + command + "\n```\n\n" + header +
                   " sky P@R100 | vanilla P@R100 | sky R@P100 | vanilla R@P100 |\n" + separator +
                   "---|---|---|---|\n";
  std::string json = "{\n  \"experiment\": \"" + o.name + "\",\n  \"command\": \"" + command +
                     "\",\n  \"rows\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    md += r.columns + Format(" %.0f %% | %.0f %% | %.0f %% | %.0f %% |\n",
                             100 * r.sky->summary.precision_at_full_recall,
                             100 * r.vanilla->summary.precision_at_full_recall,
                             100 * r.sky->summary.recall_at_full_precision,
                             100 * r.vanilla->summary.recall_at_full_precision);
    json += "    {" + r.json + "\"sky\": " + SummaryJson(*r.sky) +
            ", \"vanilla\": " + SummaryJson(*r.vanilla) + "}" +
            (i + 1 < rows.size() ? ",\n" : "\n");
  }
  md +=
      "\nP@R100: precision at 100 % recall (every match accepted); R@P100: recall at 100 % "
      "precision. Plots: pr_sky.svg, pr_vanilla.svg, correspondence.svg.\n\n" +
      notes;
  json += "  ]\n}\n";
  SKYLOC_TRY(WriteFile(o.out + "/results.md", md));
  SKYLOC_TRY(WriteFile(o.out + "/metrics.json", json));
  SKYLOC_TRY(WriteFile(o.out + "/pr_sky.svg", PrPlotSvg("SeqSLAM (sky)", rows, true)));
  SKYLOC_TRY(WriteFile(o.out + "/pr_vanilla.svg", PrPlotSvg("SeqSLAM (vanilla)", rows, false)));
  SKYLOC_TRY(WriteFile(o.out + "/correspondence.svg",
                       CorrespondenceSvg(rows, o.experiment.tolerance_frames)));
  return Status::Ok();
}

void PrintProgress(const char* what, void* /*context*/) {
  std::fprintf(stderr, "skyloc experiment: rendering %s\n", what);
}

std::string CommonNotes(const sim::ExperimentOptions& e) {
  return Format(
      "Images %dx%d (equidistant 185 degrees), sky descriptor %d SH bands, frames every "
      "%.3g m with +-20 %% speed jitter, SeqSLAM ds %d (unless stated), v %.1f..%.1f, "
      "R %d, Rwindow %d, centred window. Ground truth: the nearest reference frame by "
      "position; correct within %d frames; no truth farther than %.3g m.\n",
      e.width, e.height, e.bands, e.spacing_m, e.seqslam.sequence_length,
      static_cast<double>(e.seqslam.v_min), static_cast<double>(e.seqslam.v_max),
      e.seqslam.contrast_window, e.seqslam.uniqueness_window, e.tolerance_frames, e.max_offset_m);
}

}  // namespace

int RunExperiment(std::span<char* const> args) {
  for (char* const a : args) {
    if (IsHelpFlag(a)) {
      std::fputs(kUsage, stdout);
      return kExitOk;
    }
  }
  Options o;
  if (const int rc = ParseArgs(args, &o); rc != kExitOk)
    return rc;
  std::string command = "skyloc experiment";
  for (char* const a : args)
    command += std::string(" ") + a;

  std::vector<Row> rows;
  Status status;
  // Results live here so the rows can point at them.
  std::vector<sim::TiltRow> tilt;
  std::vector<sim::ManoeuvreRow> manoeuvre;
  std::vector<sim::AntsRow> ants;
  std::string header, separator;
  if (o.name == "tilt") {
    const int differences[] = {0, 10, 20, 30, 40, 50, 60};
    status = sim::RunTiltExperiment(o.experiment, differences, &tilt, PrintProgress, nullptr);
    header = "| tilt difference | reference / query tilt |";
    separator = "|---|---|";
    for (const sim::TiltRow& r : tilt) {
      rows.push_back({Format("%.0f deg", r.tilt_difference_deg),
                      Format("| %.0f° | %+.0f° / %+.0f° |", r.tilt_difference_deg,
                             r.reference_tilt_deg, r.query_tilt_deg),
                      Format("\"tilt_difference_deg\": %.0f, \"reference_tilt_deg\": %.0f, "
                             "\"query_tilt_deg\": %.0f, ",
                             r.tilt_difference_deg, r.reference_tilt_deg, r.query_tilt_deg),
                      &r.sky, &r.vanilla});
    }
  } else if (o.name == "manoeuvre") {
    const int ds[] = {1, 10, 20};
    status = sim::RunManoeuvreExperiment(o.experiment, ds, &manoeuvre, PrintProgress, nullptr);
    header = "| world | ds |";
    separator = "|---|---|";
    for (const sim::ManoeuvreRow& r : manoeuvre) {
      rows.push_back({Format("%s ds %d", sim::WorldKindName(r.world), r.sequence_length),
                      Format("| %s | %d |", sim::WorldKindName(r.world), r.sequence_length),
                      Format("\"world\": \"%s\", \"ds\": %d, ", sim::WorldKindName(r.world),
                             r.sequence_length),
                      &r.sky, &r.vanilla});
    }
  } else {
    if (!o.spacing_given)
      o.experiment.spacing_m = 0.05;
    o.experiment.max_offset_m = 0.25;
    const double heights[] = {0.01, 0.1};
    status =
        sim::RunAntsExperiment(o.experiment, o.data_dir, heights, &ants, PrintProgress, nullptr);
    header = "| query route | same ant | camera height | frames with truth |";
    separator = "|---|---|---|---|";
    for (const sim::AntsRow& r : ants) {
      rows.push_back({Format("%s %.2f m", r.query.c_str(), r.camera_height_m),
                      Format("| %s | %s | %.2f m | %.0f %% |", r.query.c_str(),
                             r.same_ant ? "yes" : "no", r.camera_height_m, 100 * r.truth_fraction),
                      Format("\"query\": \"%s\", \"same_ant\": %s, \"camera_height_m\": %.3f, "
                             "\"truth_fraction\": %.4f, ",
                             r.query.c_str(), r.same_ant ? "true" : "false", r.camera_height_m,
                             r.truth_fraction),
                      &r.sky, &r.vanilla});
    }
  }
  if (!status.ok()) {
    std::fprintf(stderr, "skyloc experiment %s: %s\n", o.name.c_str(), status.message());
    return kExitFailure;
  }
  std::string notes = CommonNotes(o.experiment);
  if (o.name == "ants")
    notes += std::string("Reference route ") + sim::kAntsReferenceRoute + ".\n";
  if (const Status s = WriteOutputs(o, command, header, separator, rows, notes); !s.ok()) {
    std::fprintf(stderr, "skyloc experiment %s: %s\n", o.name.c_str(), s.message());
    return kExitFailure;
  }
  std::printf(
      "skyloc experiment %s: wrote %s/results.md, metrics.json, pr_sky.svg, "
      "pr_vanilla.svg, correspondence.svg\n",
      o.name.c_str(), o.out.c_str());
  return kExitOk;
}

}  // namespace skyloc::app
