// `skyloc experiment NAME --out DIR`: the paper's experiments on simulated runs
// (docs/RESULTS.md). Each writes DIR/results.md (a markdown table and the command that
// made it), DIR/metrics.json, precision-recall plots DIR/pr_sky.svg and DIR/pr_vanilla.svg,
// and frame correspondences DIR/correspondence.svg. The experiments are host evaluation
// code (skyloc::tools): a build without SKYLOC_HOST_EVAL says they are not in it.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "firmware/config.h"
#include "firmware/pipeline.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/dsp/route_filter.h"
#include "tools/eval_results.h"
#include "tools/experiment.h"
#include "tools/output_file.h"
#include "tools/svg_plot.h"
#include "tools/vocabulary.h"

namespace skyloc::cli {
using namespace skyloc::firmware;
using namespace skyloc::tools;
namespace {

constexpr const char* kDescription =
    "The paper's experiments on simulated runs (docs/RESULTS.md):\n"
    "  tilt       City loop, runs at tilt -30..30 paired alpha1 ~ -alpha2 (differences\n"
    "             0..60): recall at 100 % precision, sky vs vanilla SeqSLAM\n"
    "  manoeuvre  forest (BMX) and repetitive (Disposal) worlds, reference at noon vs a\n"
    "             dawn run with zig-zag and bumps: precision at 100 % recall, ds 1/10/20\n"
    "  ants       Seville habitat, ant1_route1 as reference vs other routes of ant 1 and\n"
    "             of other ants, at ant height (0.01 m) and robot height (0.1 m)\n"
    "  speed      forest and city, sampled in time at 10 fps: a taught run with stops vs\n"
    "             repeats at 0.5x/1x/2x, with and without stops, level and +-15 deg bumps;\n"
    "             OpenSeqSLAM vs the route filter (sky), ds 1/5/10/20\n"
    "  heading    manoeuvre's runs (zig-zag +-20 deg, bumps +-15 deg): heading error of the\n"
    "             horizon-strip cross-correlation and of 1D SURF + RANSAC against the\n"
    "             poses, on frames the route filter matches correctly\n"
    "  surf1d     the 1D SURF paper's ROC experiment, turning on the spot in the city\n"
    "             (own options: skyloc experiment surf1d --help)\n"
    "The sky descriptor is the robot's (firmware::SkyDescriptorOptionsFrom: 120 bands on the\n"
    "oversampled grid, unit_l2) unless --bands, --grid or --normalisation say otherwise; the\n"
    "published tables used --bands 120 --grid auto.\n";

struct Options {
  std::string name, out, data_dir = "../shared/data/seville2009";
  std::string vocabulary_path;  // --vocab: FAB-MAP 2.0 (tilt, manoeuvre)
  tools::ExperimentOptions experiment;
  bool spacing_given = false;
};

constexpr const char* kExperiments[] = {"tilt", "manoeuvre", "ants", "speed", "heading"};

// Parses and checks the command line; kRun or the outcome to exit with.
ParseOutcome ParseArgs(std::span<char* const> args, Options* o) {
  tools::ExperimentOptions& e = o->experiment;
  firmware::DescriptorConfig& descriptor = e.config.descriptor;
  std::vector<std::string> name;
  OptionTable t("experiment", "tilt|manoeuvre|ants|speed|heading|surf1d --out DIR [options]",
                kDescription);
  t.Positional("NAME", "the experiment: tilt, manoeuvre, ants, speed, heading or surf1d", 0, 1,
               &name);
  t.Text("--out", "DIR", "the folder the results are written to (required)", &o->out);
  t.Int("--width", "W", "image width in pixels (default 320)", 16, 4096, &e.width);
  t.Int("--height", "H", "image height in pixels (default 240)", 16, 4096, &e.height);
  static_assert(firmware::DescriptorConfig{}.bands == 120, "the help states the default bands");
  t.Int("--bands", "N",
        "SH bands of the sky descriptor (default 120 on the oversampled grid, the robot's)", 2, 200,
        &descriptor.bands);
  AddDescriptorChoices(&t, &descriptor.grid, &descriptor.normalisation);
  t.Choice(
      "--route-storage",
      "how the route filter holds the taught descriptors, as [capacities] route_storage: "
      "codes8, codes16, bfloat16 or float32 (default: the firmware's default)",
      {{dsp::ReferenceStorageName(dsp::ReferenceStorage::kFloat32),
        dsp::ReferenceStorage::kFloat32},
       {dsp::ReferenceStorageName(dsp::ReferenceStorage::kBFloat16),
        dsp::ReferenceStorage::kBFloat16},
       {dsp::ReferenceStorageName(dsp::ReferenceStorage::kCodes8), dsp::ReferenceStorage::kCodes8},
       {dsp::ReferenceStorageName(dsp::ReferenceStorage::kCodes16),
        dsp::ReferenceStorage::kCodes16}},
      &e.config.capacities.route_storage);
  t.Int("--search-window", "N",
        "route filter: compare each frame with the rows within +-N of the last best row and "
        "every other row once every --refresh-frames frames ([seqslam] search_window; "
        "default 0: every row every frame)",
        0, dsp::kMaxSearchWindow, &e.filter.search_window);
  t.Int("--refresh-frames", "F",
        "route filter with --search-window: frames between two comparisons of a row outside "
        "the window ([seqslam] refresh_frames, 1..1000)",
        1, dsp::kMaxRefreshFrames, &e.filter.refresh_frames);
  t.Int("--strip-columns", "N",
        "heading: the horizon strip's columns over 360 degrees ([heading] strip_columns; "
        "default 360; at least 148, 1D SURF's widest filter)",
        148, 4096, &e.config.heading.strip.n_azimuth);
  t.Choice("--stored-strip-bits",
           "heading: bits a column of the route's strip, 4 (16 levels over the strip's own "
           "range, as the firmware keeps it; default) or 8 (a byte, route formats 4 and 5); "
           "the query strip stays in bytes",
           {{"4", 4}, {"8", 8}}, &e.stored_strip_bits);
  t.Number("--spacing", "M", "frame spacing in metres (default 1; ants 0.05)", {0.001, 100},
           &e.frames.frame_spacing_m);
  t.Int("--frames", "N", "at most N frames a run (default: whole routes)", 20, 1000000,
        &e.max_frames);
  t.Count("--seed", "N", "procedural world seed (default 1)", &e.world_seed);
  t.Number("--lateral", "M",
           "speed: every repeat wanders sideways off the taught line within +-M metres "
           "(default 0: on it; skyloc simulate --lateral)",
           {0, 5}, &e.lateral_m);
  t.Text("--data", "DIR", "Seville data folder (default ../shared/data/seville2009)", &o->data_dir);
  t.Choice("--attitude",
           "the gravity-aligned descriptor's zenith (tilt, manoeuvre, speed): imu (the "
           "simulated IMU with noise and bias through the attitude filter; default), truth "
           "(the true poses), none, image (estimated from each frame's sky mask, experimental)",
           {{"none", tools::AttitudeInput::kNone},
            {"truth", tools::AttitudeInput::kTruth},
            {"imu", tools::AttitudeInput::kSimulatedImu},
            {"image", tools::AttitudeInput::kImage}},
           &e.attitude);
  t.Choice("--zenith",
           "--attitude image's method: skyline (the skyline's mean plane; default) or "
           "centroid (the sky's centroid)",
           {{"skyline", dsp::ZenithMethod::kSkylinePlane},
            {"centroid", dsp::ZenithMethod::kSkyCentroid}},
           &e.zenith.method);
  t.Number("--cap-elevation", "DEG",
           "the cap's lower edge (default: from the experiment's largest tilt and the 185 "
           "degree lens, docs/SKY_DESCRIPTOR.md)",
           {0, 80}, &e.cap_elevation_deg);
  t.Text("--vocab", "VOCAB",
         "tilt, manoeuvre: add FAB-MAP 2.0 on the visible images (the fabmap column) with a "
         "vocabulary from `skyloc fabmap-train`, trained on a run of another world "
         "(docs/FABMAP.md)",
         &o->vocabulary_path);
  if (const ParseOutcome outcome = t.Parse(args); outcome != ParseOutcome::kRun)
    return outcome;
  if (name.empty())
    return t.Refuse("name the experiment: tilt, manoeuvre, ants, speed, heading or surf1d");
  o->name = name.front();
  if (std::find(std::begin(kExperiments), std::end(kExperiments), o->name) ==
      std::end(kExperiments))
    return t.Refuse("unknown experiment '" + o->name +
                    "' (tilt, manoeuvre, ants, speed, heading, surf1d)");
  if ((t.Given("--strip-columns") || t.Given("--stored-strip-bits")) && o->name != "heading")
    return t.Refuse("--strip-columns and --stored-strip-bits are for heading");
  if (t.Given("--vocab") && o->name != "tilt" && o->name != "manoeuvre")
    return t.Refuse("--vocab (FAB-MAP) is for tilt and manoeuvre");
  if (o->out.empty())
    return t.Refuse("--out DIR is required");
  // The route filter's own rule for the pair (refresh_frames only with a window).
  if (const dsp::SeqSlamError f = dsp::ValidateRouteFilterParams(e.filter);
      f != dsp::SeqSlamError::kOk)
    return t.Refuse(std::string("--search-window, --refresh-frames: ") +
                    dsp::SeqSlamErrorMessage(f));
  o->spacing_given = t.Given("--spacing");
  firmware::ResolveDescriptorGrid(&descriptor);
  return ParseOutcome::kRun;
}

// The methods an experiment compares, in column order: the JSON and file name of each
// ("sky" -> pr_sky.svg) and its title.
struct MethodName {
  const char* key;
  const char* title;
};

// A row of any experiment, as the writers see it: one score per method, in that order.
struct Row {
  std::string label;    // also the plot legend
  std::string columns;  // markdown cells before the metrics
  std::string json;     // JSON fields before the metrics
  std::vector<const tools::MethodScore*> scores;
};

// One method's scores: the fields every metrics.json shares (docs/METRICS.md).
// Appended, not "{" + ...: GCC 12 at -O3 warns a false -Wrestrict on the temporary.
std::string SummaryJson(const tools::MethodScore& m) {
  std::string json = "{";
  json += tools::ScoreFieldsJson(m.summary, m.curve);
  json += "}";
  return json;
}

// Precision-recall curves of one method, one per row.
std::string PrPlot(const char* title, const std::vector<Row>& rows, std::size_t method) {
  std::vector<PrCurve> curves;
  for (const Row& r : rows)
    curves.push_back({r.label, r.scores[method]->curve, LineDash::kSolid});
  return PrPlotSvg(title, curves);
}

// Frame correspondences (the paper's Figs. 5a, 8, 9): for every row, one panel per method
// (the last method first: vanilla left of sky, as the paper).
std::string CorrespondencePlot(const std::vector<Row>& rows, std::span<const MethodName> methods) {
  std::vector<CorrespondencePanel> panels;
  for (const Row& r : rows) {
    for (std::size_t k = methods.size(); k-- > 0;) {
      const tools::MethodScore& m = *r.scores[k];
      CorrespondencePanel panel{std::string(methods[k].key) + ": " + r.label, {}, 1, {}};
      for (std::size_t q = 0; q < m.truth.size(); ++q) {
        panel.ground_truth.push_back(m.truth[q].nearest);
        panel.reference_frames =
            std::max({panel.reference_frames, m.truth[q].nearest + 1, m.matched[q] + 1});
        if (m.matched[q] >= 0)
          panel.matches.push_back({static_cast<int>(q), m.matched[q], m.correct[q]});
      }
      panels.push_back(std::move(panel));
    }
  }
  return CorrespondenceSvg(panels, static_cast<int>(methods.size()));
}

Status WriteOutputs(const Options& o, const std::string& command, const std::string& header,
                    const std::string& separator, std::span<const MethodName> methods,
                    const std::vector<Row>& rows, const std::string& notes) {
  if (::mkdir(o.out.c_str(), 0755) != 0 && errno != EEXIST)
    return Status::FromErrno(errno, "cannot create '%s'", o.out.c_str());
  std::string md = "# skyloc experiment " + o.name + "\n\n```\n" + command + "\n```\n\n" + header;
  std::string rule = separator;
  for (const char* metric : {"P@R100", "R@P100"}) {
    for (const MethodName& m : methods) {
      md += Format(" %s %s |", m.key, metric);
      rule += "---|";
    }
  }
  md += "\n" + rule + "\n";
  std::string json = tools::MetricsJsonHead("experiment") +
                     "  \"experiment\": " + tools::JsonString(o.name) +
                     ",\n  \"command\": " + tools::JsonString(command) + ",\n  \"rows\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const Row& r = rows[i];
    md += r.columns;
    for (const tools::MethodScore* m : r.scores)
      md += Format(" %.0f %% |", 100 * m->summary.precision_at_full_recall);
    for (const tools::MethodScore* m : r.scores)
      md += Format(" %.0f %% |", 100 * m->summary.recall_at_full_precision);
    md += "\n";
    json += "    {" + r.json;
    for (std::size_t k = 0; k < methods.size(); ++k)
      json +=
          (k ? ", \"" : "\"") + std::string(methods[k].key) + "\": " + SummaryJson(*r.scores[k]);
    json += std::string("}") + (i + 1 < rows.size() ? ",\n" : "\n");
  }
  std::string plots;
  for (const MethodName& m : methods)
    plots += std::string("pr_") + m.key + ".svg, ";
  md +=
      "\nP@R100: precision at 100 % recall (every match accepted); R@P100: recall at 100 % "
      "precision. Plots: " +
      plots + "correspondence.svg.\n\n" + notes;
  json += "  ]\n}\n";
  SKYLOC_TRY(WriteText(o.out + "/results.md", md));
  SKYLOC_TRY(WriteText(o.out + "/metrics.json", json));
  for (std::size_t k = 0; k < methods.size(); ++k) {
    SKYLOC_TRY(
        WriteText(o.out + "/pr_" + methods[k].key + ".svg", PrPlot(methods[k].title, rows, k)));
  }
  SKYLOC_TRY(WriteText(o.out + "/correspondence.svg", CorrespondencePlot(rows, methods)));
  return Status::Ok();
}

constexpr MethodName kDescriptorMethods[] = {
    {"sky", "SeqSLAM (sky)"},
    {"vanilla", "SeqSLAM (vanilla)"},
    {"sky_filter", "Route filter (sky)"},
    {"sky_cap", "SeqSLAM (sky, gravity-aligned cap)"},
    {"sky_cap_filter", "Route filter (sky, gravity-aligned cap)"}};
// The column after them in tilt and manoeuvre with --vocab.
constexpr MethodName kFabmapMethod = {"fabmap", "FAB-MAP 2.0 (visible, SIFT)"};
constexpr MethodName kMatcherMethods[] = {
    {"openseqslam", "OpenSeqSLAM (sky)"},
    {"filter", "Route filter (sky)"},
    {"filter_cap", "Route filter (sky, gravity-aligned cap)"}};
// The methods without the gravity-aligned columns (--attitude none, and ants).
constexpr std::size_t kDescriptorMethodsWithoutCap = 3;
constexpr std::size_t kMatcherMethodsWithoutCap = 2;

// The firmware's state machine (default [state] settings, the filter's motion limits)
// over a filter run: how many frames it shows LOCALISED, and how many of those are right.
std::pair<int, int> LocalisedFrames(const tools::MethodScore& m) {
  Config config;
  config.seqslam.matcher = Matcher::kRouteFilter;
  const std::vector<dsp::LocalisationState> states = ReplayStateMachine(config, m.matches);
  int localised = 0, correct = 0;
  for (std::size_t t = 0; t < states.size(); ++t) {
    if (states[t] == dsp::LocalisationState::kLocalised) {
      ++localised;
      correct += m.correct[t] ? 1 : 0;
    }
  }
  return {localised, correct};
}

void PrintProgress(const char* what) {
  std::fprintf(stderr, "skyloc experiment: rendering %s\n", what);
}

std::string CommonNotes(const tools::ExperimentOptions& e) {
  const std::string sampling =
      e.frames.sampling == sim::Sampling::kTime
          ? Format(
                "frames at %.3g fps along a speed profile (cruise %.3g m/s x the run's speed "
                "ratio, a %.3g s stop at the start and %d more of %.3g-%.3g s unless stated)",
                e.fps, e.frames.speed.cruise_mps, e.frames.speed.start_stop_s, e.frames.speed.stops,
                e.frames.speed.stop_min_s, e.frames.speed.stop_max_s) +
                (e.lateral_m > 0
                     ? Format("; every repeat wanders sideways off the taught line within +-%.3g m",
                              e.lateral_m)
                     : std::string())
          : Format("frames every %.3g m with +-20 %% speed jitter", e.frames.frame_spacing_m);
  return Format(
             "Images %dx%d (equidistant 185 degrees), sky descriptor %d SH bands on the "
             "\"%s\" grid, normalisation %s, ",
             e.width, e.height, e.config.descriptor.bands,
             firmware::NameOf(e.config.descriptor.grid),
             dsp::AmplitudeNormalisationName(e.config.descriptor.normalisation)) +
         sampling +
         Format(
             ". OpenSeqSLAM: ds %d (unless stated), v %.1f..%.1f, R %d, Rwindow %d, centred "
             "window. Route filter: ds as OpenSeqSLAM's, K %d, keyframe noise factor %.3g, "
             "Rwindow %d, causal, route held as %s%s. Ground truth: the reference frames tied "
             "(within 1 cm) "
             "for nearest by position; correct within %d frames of them; no truth farther "
             "than %.3g m.\n",
             e.seqslam.sequence_length, static_cast<double>(e.seqslam.v_min),
             static_cast<double>(e.seqslam.v_max), e.seqslam.contrast_window,
             e.seqslam.uniqueness_window, e.filter.max_advance,
             static_cast<double>(e.filter.keyframe_noise_factor), e.filter.uniqueness_window,
             dsp::ReferenceStorageName(e.config.capacities.route_storage),
             e.filter.search_window > 0
                 ? Format(", search window +-%d rows, other rows every %d frames",
                          e.filter.search_window, e.filter.refresh_frames)
                       .c_str()
                 : "",
             e.tolerance_frames, e.max_offset_m);
}

std::string HeadingCell(const dsp::HeadingErrorSummary& e) {
  if (e.estimated == 0)
    return Format("— (0 of %d)", e.frames);
  return Format("%.2f° / %.2f° (%d of %d)", e.median_deg, e.p90_deg, e.estimated, e.frames);
}

// `skyloc experiment heading`: its own tables (errors, not precision-recall).
int RunHeading(const Options& o, const std::string& command) {
  std::vector<tools::HeadingRow> rows;
  if (Status s = tools::RunHeadingExperiment(o.experiment, &rows, PrintProgress); !s.ok()) {
    return Failed("experiment heading", s);
  }
  // All worlds together: the done-when figure.
  std::vector<double> pooled_correlation, pooled_surf, pooled_answer;
  int pooled_frames = 0, pooled_uncertain = 0, pooled_wrong = 0, pooled_wrong_certain = 0;
  for (const tools::HeadingRow& r : rows) {
    pooled_frames += r.correlation.frames;
    pooled_uncertain += r.uncertain_frames;
    pooled_wrong += r.wrong_frames;
    pooled_wrong_certain += r.wrong_certain_frames;
    pooled_answer.insert(pooled_answer.end(), r.answer_errors_deg.begin(),
                         r.answer_errors_deg.end());
    pooled_correlation.insert(pooled_correlation.end(), r.correlation_errors_deg.begin(),
                              r.correlation_errors_deg.end());
    pooled_surf.insert(pooled_surf.end(), r.surf_errors_deg.begin(), r.surf_errors_deg.end());
  }
  const dsp::HeadingErrorSummary all_correlation =
      dsp::SummariseHeadingErrors(pooled_correlation, pooled_frames);
  const dsp::HeadingErrorSummary all_surf = dsp::SummariseHeadingErrors(pooled_surf, pooled_frames);
  const dsp::HeadingErrorSummary all_answer =
      dsp::SummariseHeadingErrors(pooled_answer, pooled_frames);
  std::string md = "# skyloc experiment heading\n\n```\n" + command +
                   "\n```\n\nHeading error (absolute, median / 90th percentile, degrees; frames "
                   "with an estimate of the correctly matched ones):\n\n"
                   "| world | query frames | correctly matched | (b) cross-correlation | "
                   "(a) 1D SURF + RANSAC | heading_deg (the firmware's answer) | "
                   "(b) uncertain: (a) run | (a) where run | (b) wrong (> 10°): of them certain | "
                   "(b) tilt <= 10° | (b) tilt > 10° |\n"
                   "|---|---|---|---|---|---|---|---|---|---|---|\n";
  std::string json =
      tools::MetricsJsonHead("experiment") +
      "  \"experiment\": \"heading\",\n  \"command\": " + tools::JsonString(command) +
      ",\n  \"rows\": [\n";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const tools::HeadingRow& r = rows[i];
    md +=
        Format("| %s | %d | %d | %s | %s | %s | %d | %s | %d of %d | %s | %s |\n",
               sim::WorldKindName(r.world), r.query_frames, r.match.summary.correct,
               HeadingCell(r.correlation).c_str(), HeadingCell(r.surf).c_str(),
               HeadingCell(r.answer).c_str(), r.uncertain_frames,
               HeadingCell(r.surf_where_uncertain).c_str(), r.wrong_certain_frames, r.wrong_frames,
               HeadingCell(r.correlation_level).c_str(), HeadingCell(r.correlation_tilted).c_str());
    json += Format("    {\"world\": \"%s\", \"query_frames\": %d, \"correct_matches\": %d, ",
                   sim::WorldKindName(r.world), r.query_frames, r.match.summary.correct) +
            "\"correlation\": " + tools::HeadingSummaryJson(r.correlation) +
            ", \"surf\": " + tools::HeadingSummaryJson(r.surf) +
            ", \"answer\": " + tools::HeadingSummaryJson(r.answer) +
            Format(", \"uncertain_frames\": %d", r.uncertain_frames) +
            ", \"surf_where_uncertain\": " + tools::HeadingSummaryJson(r.surf_where_uncertain) +
            Format(", \"wrong_frames\": %d, \"wrong_certain_frames\": %d", r.wrong_frames,
                   r.wrong_certain_frames) +
            ", \"correlation_level\": " + tools::HeadingSummaryJson(r.correlation_level) +
            ", \"correlation_tilted\": " + tools::HeadingSummaryJson(r.correlation_tilted) + "}" +
            (i + 1 < rows.size() ? ",\n" : "\n");
  }
  md +=
      Format("| all | | | %s | %s | %s | %d | | %d of %d | | |\n",
             HeadingCell(all_correlation).c_str(), HeadingCell(all_surf).c_str(),
             HeadingCell(all_answer).c_str(), pooled_uncertain, pooled_wrong_certain, pooled_wrong);
  json += "  ],\n  \"all\": {\"correlation\": " + tools::HeadingSummaryJson(all_correlation) +
          ", \"surf\": " + tools::HeadingSummaryJson(all_surf) +
          ", \"answer\": " + tools::HeadingSummaryJson(all_answer) +
          Format(", \"uncertain_frames\": %d, \"wrong_frames\": %d, \"wrong_certain_frames\": %d",
                 pooled_uncertain, pooled_wrong, pooled_wrong_certain) +
          "}\n}\n";
  const dsp::HorizonStripOptions& strip = o.experiment.config.heading.strip;
  md += Format(
      "\nTruth: the query pose's yaw minus the matched reference frame's (counter-clockwise "
      "positive, the firmware's heading_deg). Matches: the route filter (ds %d) on the sky "
      "descriptor, correct within %d frames. Strips: %d columns, %d rows over %.3g..%.3g "
      "degrees above the body's horizon, from the UV frame, rounded to bytes; the route's "
      "strip at %d bits a column. Tilt: the query body's z from the zenith. The target: "
      "median < 3 degrees and 90th percentile < 10 degrees.\n\n",
      o.experiment.seqslam.sequence_length, o.experiment.tolerance_frames, strip.n_azimuth,
      strip.band_rows, strip.elevation_min_deg, strip.elevation_max_deg,
      o.experiment.stored_strip_bits);
  md += CommonNotes(o.experiment);
  // Every estimate in full precision (%.17g round-trips a double): two builds that give the
  // same headings give the same file. Empty cells: that way gave no heading.
  std::string frames_csv =
      "world,query_frame,route_frame,truth_deg,uncertain,correlation_deg,surf_deg,surf_inliers\n";
  for (const tools::HeadingRow& r : rows) {
    for (const tools::HeadingRow::Frame& f : r.frames) {
      const dsp::HeadingEstimate& e = f.estimate;
      frames_csv += Format("%s,%d,%d,%.17g,%d,", sim::WorldKindName(r.world), f.query, f.route,
                           f.truth_deg, e.uncertain ? 1 : 0);
      frames_csv += e.has_correlation ? Format("%.17g", e.correlation_deg) : std::string();
      frames_csv += e.has_surf ? Format(",%.17g,%d\n", e.surf_deg, e.surf_inliers) : ",,\n";
    }
  }
  if (::mkdir(o.out.c_str(), 0755) != 0 && errno != EEXIST) {
    std::fprintf(stderr, "skyloc experiment heading: cannot create '%s': %s\n", o.out.c_str(),
                 std::strerror(errno));
    return kExitFailure;
  }
  for (const auto& [name, text] :
       {std::pair{"/results.md", &md}, {"/metrics.json", &json}, {"/frames.csv", &frames_csv}}) {
    if (Status s = WriteText(o.out + name, *text); !s.ok()) {
      return Failed("experiment heading", s);
    }
  }
  std::fputs(md.c_str(), stdout);
  std::printf("skyloc experiment heading: wrote %s/: results.md, metrics.json, frames.csv\n",
              o.out.c_str());
  return kExitOk;
}

}  // namespace

namespace {

// An experiment's table: its rows (pointing into the results held here), the markdown
// header, and the methods scored in its columns.
struct Table {
  std::vector<tools::TiltRow> tilt;
  std::vector<tools::ManoeuvreRow> manoeuvre;
  std::vector<tools::AntsRow> ants;
  std::vector<tools::SpeedRow> speed;
  std::vector<Row> rows;
  std::string header, separator;
  std::vector<MethodName> methods;
  bool cap = false;     // the gravity-aligned cap's columns
  bool fabmap = false;  // FAB-MAP's column

  // Tilt and manoeuvre rows: the descriptor methods in use, then FAB-MAP.
  template <typename R>
  std::vector<const tools::MethodScore*> DescriptorScores(const R& r) const {
    std::vector<const tools::MethodScore*> s = {&r.sky, &r.vanilla, &r.sky_filter};
    if (cap) {
      s.push_back(&r.sky_cap);
      s.push_back(&r.sky_cap_filter);
    }
    if (fabmap)
      s.push_back(&r.fabmap);
    return s;
  }
};

Status RunTiltTable(const Options& o, Table* t) {
  const int differences[] = {0, 10, 20, 30, 40, 50, 60};
  SKYLOC_TRY(tools::RunTiltExperiment(o.experiment, differences, &t->tilt, PrintProgress));
  t->header = "| tilt difference | reference / query tilt |";
  t->separator = "|---|---|";
  for (const tools::TiltRow& r : t->tilt) {
    t->rows.push_back({Format("%.0f deg", r.tilt_difference_deg),
                       Format("| %.0f° | %+.0f° / %+.0f° |", r.tilt_difference_deg,
                              r.reference_tilt_deg, r.query_tilt_deg),
                       Format("\"tilt_difference_deg\": %.6f, \"reference_tilt_deg\": %.6f, "
                              "\"query_tilt_deg\": %.6f, ",
                              r.tilt_difference_deg, r.reference_tilt_deg, r.query_tilt_deg),
                       t->DescriptorScores(r)});
  }
  return Status::Ok();
}

Status RunManoeuvreTable(const Options& o, Table* t) {
  const int ds[] = {1, 10, 20};
  SKYLOC_TRY(tools::RunManoeuvreExperiment(o.experiment, ds, &t->manoeuvre, PrintProgress));
  t->header = "| world | ds |";
  t->separator = "|---|---|";
  for (const tools::ManoeuvreRow& r : t->manoeuvre) {
    t->rows.push_back(
        {Format("%s ds %d", sim::WorldKindName(r.world), r.sequence_length),
         Format("| %s | %d |", sim::WorldKindName(r.world), r.sequence_length),
         Format("\"world\": \"%s\", \"ds\": %d, ", sim::WorldKindName(r.world), r.sequence_length),
         t->DescriptorScores(r)});
  }
  return Status::Ok();
}

Status RunSpeedTable(Options* o, Table* t) {
  o->experiment.frames.sampling = sim::Sampling::kTime;
  const int ds[] = {1, 5, 10, 20};
  SKYLOC_TRY(tools::RunSpeedExperiment(o->experiment, ds, &t->speed, PrintProgress));
  t->methods.assign(std::begin(kMatcherMethods), std::end(kMatcherMethods));
  if (!t->cap)
    t->methods.resize(kMatcherMethodsWithoutCap);
  t->header =
      "| world | repeat speed | repeat stops | bumps | frames | ds | filter LOCALISED correct |";
  t->separator = "|---|---|---|---|---|---|---|";
  for (const tools::SpeedRow& r : t->speed) {
    const auto [localised, correct] = LocalisedFrames(r.filter);
    t->rows.push_back(
        {Format("%s %.1fx %s %s ds %d", sim::WorldKindName(r.world), r.speed_ratio,
                r.stops ? "stops" : "no-stops", r.bumps_deg > 0 ? "bumps" : "level",
                r.sequence_length),
         Format("| %s | %.1fx | %s | %s | %d | %d | %d of %d |", sim::WorldKindName(r.world),
                r.speed_ratio, r.stops ? "yes" : "no",
                r.bumps_deg > 0 ? Format("±%.0f°", r.bumps_deg).c_str() : "level", r.query_frames,
                r.sequence_length, correct, localised),
         Format("\"world\": \"%s\", \"speed_ratio\": %.6f, \"stops\": %s, \"bumps_deg\": %.6f, "
                "\"query_frames\": %d, \"ds\": %d, \"filter_localised\": %d, "
                "\"filter_localised_correct\": %d, ",
                sim::WorldKindName(r.world), r.speed_ratio, r.stops ? "true" : "false", r.bumps_deg,
                r.query_frames, r.sequence_length, localised, correct),
         {&r.openseqslam, &r.filter, &r.filter_cap}});
  }
  return Status::Ok();
}

Status RunAntsTable(Options* o, Table* t) {
  if (!o->spacing_given)
    o->experiment.frames.frame_spacing_m = 0.05;
  o->experiment.max_offset_m = 0.25;
  const double heights[] = {0.01, 0.1};
  SKYLOC_TRY(
      tools::RunAntsExperiment(o->experiment, o->data_dir, heights, &t->ants, PrintProgress));
  t->header = "| query route | same ant | camera height | frames with truth |";
  t->separator = "|---|---|---|---|";
  for (const tools::AntsRow& r : t->ants) {
    t->rows.push_back({Format("%s %.2f m", r.query.c_str(), r.camera_height_m),
                       Format("| %s | %s | %.2f m | %.0f %% |", r.query.c_str(),
                              r.same_ant ? "yes" : "no", r.camera_height_m, 100 * r.truth_fraction),
                       Format("\"query\": \"%s\", \"same_ant\": %s, \"camera_height_m\": %.6f, "
                              "\"truth_fraction\": %.6f, ",
                              r.query.c_str(), r.same_ant ? "true" : "false", r.camera_height_m,
                              r.truth_fraction),
                       {&r.sky, &r.vanilla, &r.sky_filter}});
  }
  return Status::Ok();
}

// The notes under the table: the gravity-aligned cap and its zenith against the truth
// (the zenith table is also printed), FAB-MAP's vocabulary, the ants' reference route.
std::string TableNotes(const Options& o, const Table& t, const tools::Vocabulary& vocabulary) {
  std::string notes = CommonNotes(o.experiment);
  if (t.cap && o.name != "ants") {
    notes += Format(
        "Gravity-aligned cap (sky_cap columns): zenith from %s; lower edge %s, taper %.3g "
        "degrees.\n",
        o.experiment.attitude == tools::AttitudeInput::kTruth ? "the true poses"
        : o.experiment.attitude == tools::AttitudeInput::kImage
            ? (o.experiment.zenith.method == dsp::ZenithMethod::kSkylinePlane
                   ? "the image alone (dsp::ZenithEstimator: the skyline's mean plane)"
                   : "the image alone (dsp::ZenithEstimator: the sky's centroid)")
            : "the simulated IMU (noise and bias on) through the attitude filter",
        o.experiment.cap_elevation_deg < 0
            ? "from the experiment's largest tilt (dsp::CapElevationForTilt)"
            : Format("%.3g degrees", o.experiment.cap_elevation_deg).c_str(),
        o.experiment.config.attitude.cap_taper_deg);
  }
  if (t.cap && (o.name == "tilt" || o.name == "manoeuvre")) {
    // The cap's zenith against the true poses, per scored pair of runs.
    std::string table =
        "\nThe cap's zenith against the true poses (degrees: mean / p95 / max over the run's "
        "frames; frames with no estimate, then assumed level):\n\n"
        "| row | reference run | query run | no estimate (ref / query) |\n|---|---|---|---|\n";
    auto cell = [](const tools::ZenithError& z) {
      return Format("%.2f / %.2f / %.2f", z.mean_deg, z.p95_deg, z.max_deg);
    };
    auto add = [&](const std::string& label, const tools::ZenithError& ref,
                   const tools::ZenithError& query) {
      table += Format("| %s | %s | %s | %d / %d |\n", label.c_str(), cell(ref).c_str(),
                      cell(query).c_str(), ref.no_estimate, query.no_estimate);
    };
    for (std::size_t i = 0; i < t.tilt.size(); ++i)
      add(t.rows[i].label, t.tilt[i].reference_zenith, t.tilt[i].query_zenith);
    for (std::size_t i = 0; i < t.manoeuvre.size(); ++i)
      add(t.rows[i].label, t.manoeuvre[i].reference_zenith, t.manoeuvre[i].query_zenith);
    std::fputs(table.c_str(), stdout);
    notes += table;
  }
  if (t.fabmap) {
    // Format holds 511 characters: the path, of any length, goes in on its own.
    notes += std::string(
                 "\nFAB-MAP 2.0 (fabmap columns, docs/FABMAP.md): each query frame's visible "
                 "image localised alone against every reference frame (no sequence") +
             (o.name == "manoeuvre" ? ": the same score on every ds row" : "") +
             "), uniqueness 1 - p(matched place). Vocabulary " + o.vocabulary_path +
             Format(
                 ": %d words, SIFT at %dx%d (at most %d a frame), %zu new-place samples, "
                 "detector p(z|e) %.2f, p(z|not e) %.2f.\n",
                 vocabulary.words, vocabulary.features.width, vocabulary.features.height,
                 vocabulary.features.max_features, vocabulary.samples.size(),
                 vocabulary.p_z_given_e, vocabulary.p_z_given_not_e);
  }
  if (o.name == "ants")
    notes += std::string("Reference route ") + tools::kAntsReferenceRoute + ".\n";
  return notes;
}

int Fail(const Options& o, const Status& s) {
  std::fprintf(stderr, "skyloc experiment %s: %s\n", o.name.c_str(), s.message());
  return kExitFailure;
}

int RunNamedExperiment(Options& o, std::span<char* const> args) {
  std::string command = "skyloc experiment";
  for (char* const a : args)
    command += std::string(" ") + a;
  if (o.name == "heading")
    return RunHeading(o, command);

  Table t;
  t.cap = o.experiment.attitude != tools::AttitudeInput::kNone;
  t.methods.assign(std::begin(kDescriptorMethods), std::end(kDescriptorMethods));
  if (!t.cap || o.name == "ants")
    t.methods.resize(kDescriptorMethodsWithoutCap);
  tools::Vocabulary vocabulary;
  t.fabmap = !o.vocabulary_path.empty();
  if (t.fabmap) {
    Result<tools::Vocabulary> v = tools::LoadVocabulary(o.vocabulary_path);
    if (!v.ok())
      return Fail(o, v.status());
    vocabulary = std::move(*v);
    o.experiment.fabmap_vocabulary = &vocabulary;
    t.methods.push_back(kFabmapMethod);
  }
  const Status status = o.name == "tilt"        ? RunTiltTable(o, &t)
                        : o.name == "manoeuvre" ? RunManoeuvreTable(o, &t)
                        : o.name == "speed"     ? RunSpeedTable(&o, &t)
                                                : RunAntsTable(&o, &t);
  if (!status.ok())
    return Fail(o, status);
  for (Row& r : t.rows)
    r.scores.resize(t.methods.size());
  const std::string notes = TableNotes(o, t, vocabulary);
  if (const Status s = WriteOutputs(o, command, t.header, t.separator, t.methods, t.rows, notes);
      !s.ok())
    return Fail(o, s);
  std::string files = "results.md, metrics.json, ";
  for (const MethodName& m : t.methods)
    files += std::string("pr_") + m.key + ".svg, ";
  std::printf("skyloc experiment %s: wrote %s/: %scorrespondence.svg\n", o.name.c_str(),
              o.out.c_str(), files.c_str());
  return kExitOk;
}

}  // namespace

int RunExperiment(std::span<char* const> args) {
  if (!args.empty() && std::strcmp(args[0], "surf1d") == 0)
    return RunSurf1dExperiment(args);
  return RunParsed(args, ParseArgs, [args](Options& o) { return RunNamedExperiment(o, args); });
}

}  // namespace skyloc::cli
