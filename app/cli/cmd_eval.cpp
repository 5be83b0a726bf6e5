// `skyloc eval`: place recognition of a query run against a reference run (two dataset
// folders): the command line over the evaluation library (tools/eval_*.h). Writes
// matches.csv, metrics.json (docs/METRICS.md), pr.svg and correspondence.svg into --out
// (docs/SEQSLAM.md, "Evaluation").
#include <algorithm>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <optional>
#include <string>
#include <system_error>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "firmware/config.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/dsp_status.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/platform/status.h"
#include "tools/eval_describe.h"
#include "tools/eval_match.h"
#include "tools/eval_results.h"
#include "tools/eval_score.h"
#include "tools/fabmap_eval.h"
#include "tools/output_file.h"
#include "tools/parallel.h"

namespace skyloc::cli {
using firmware::Config;
using firmware::Matcher;
using tools::EvalRun;
using tools::GroundTruth;
using tools::RunDescription;
using tools::ScoredDescriptor;
namespace {

constexpr const char* kDescription =
    "Matches every query frame against the reference route and scores the matches\n"
    "against the ground truth. DIRs are dataset folders (docs/DATASETS.md).\n"
    "Without --gt and --tolerance-m, both datasets need poses: the truth of a query is the\n"
    "reference recorded nearest to it, correct within --frame-tolerance frames.\n"
    "Writes OUT/matches.csv, OUT/metrics.json (docs/METRICS.md), OUT/pr.svg and\n"
    "OUT/correspondence.svg, each to a temporary file renamed into place once complete: a\n"
    "full disk leaves the previous file (or none), never a truncated one.\n"
    "Every run also replays the firmware's state machine ([state] of --config) over its\n"
    "matches: matches.csv gives each frame's state, metrics.json the share of LOCALISED\n"
    "frames that are correct. Sky runs with horizon strips also print it with frames whose\n"
    "1D SURF score against the matched frame is below 25..400 counted as no match (landmark\n"
    "confirmation, docs/RESULTS.md).\n"
    "--method fabmap is FAB-MAP 2.0 on SIFT words (docs/FABMAP.md): one run, no matcher or\n"
    "sequence length. --method surf1d is the 1D SURF recognition score (NN with RANSAC) of\n"
    "the [heading] strips through the sky lens: \"single\" (each query's best-scoring\n"
    "frame) and OpenSeqSLAM over the scores at each --ds; every query against every frame,\n"
    "slow on long routes. --camera: docs/CAMERA_FILE.md; the default lens is equidistant\n"
    "185 degrees filling the short image side (equirectangular for 2:1 images), as skyloc\n"
    "describe. --attitude dataset: docs/SKY_DESCRIPTOR.md, \"Tilt\".\n";

struct EvalOptions {
  std::string reference, query, out;
  bool force = false;  // --force: --out may hold files already
  std::string gt_file;
  double tolerance_m = -1.0;  // < 0: not given
  int frame_tolerance = 5;
  std::vector<ScoredDescriptor> methods;
  std::vector<Matcher> matchers;
  std::vector<int> ds_list;
  std::optional<int> max_advance;
  std::optional<double> keyframe_noise_factor;
  std::string config_file;
  bool batch = false, streaming = false;
  std::string vocab;                 // --vocab FILE (fabmap)
  std::optional<int> bands;          // --bands: replaces [descriptor] bands of the configuration
  bool vanilla_bytes = true;         // --vanilla-precision byte (the default) or float
  tools::DescribeSettings describe;  // its config is --config FILE, then the flags above
};

void AddOptions(OptionTable* t, EvalOptions* o) {
  const auto name = [](ScoredDescriptor d) { return tools::ScoredDescriptorName(d); };
  t->Text("--reference", "DIR", "the reference run (the taught route)", &o->reference);
  t->Text("--query", "DIR", "the query run (the repeat)", &o->query);
  t->Text("--out", "DIR", "where the results go (new or empty unless --force)", &o->out);
  t->Flag("--force", "write into an --out folder that is not empty (its results are replaced)",
          &o->force);
  t->ChoiceList("--method",
                "descriptor to score (repeat to compare; default: sky and vanilla, and fabmap "
                "with --vocab)",
                {{name(ScoredDescriptor::kSky), ScoredDescriptor::kSky},
                 {name(ScoredDescriptor::kVanilla), ScoredDescriptor::kVanilla},
                 {name(ScoredDescriptor::kFabmap), ScoredDescriptor::kFabmap},
                 {name(ScoredDescriptor::kSurf1d), ScoredDescriptor::kSurf1d}},
                &o->methods);
  t->Text("--vocab", "FILE", "fabmap: the vocabulary from skyloc fabmap-train", &o->vocab);
  t->ChoiceList("--matcher",
                "the matcher (repeat to compare; default: filter, the firmware's route filter; "
                "docs/SEQSLAM.md)",
                {{firmware::NameOf(Matcher::kRouteFilter), Matcher::kRouteFilter},
                 {firmware::NameOf(Matcher::kOpenSeqSlam), Matcher::kOpenSeqSlam}},
                &o->matchers);
  t->IntList("--ds", "N", "sequence length in frames (repeat; default: 1 10 20)", 1,
             dsp::kMaxSequenceLength, &o->ds_list);
  t->Flag("--batch",
          "openseqslam: OpenSeqSLAM's centred window (default; implies --matcher "
          "openseqslam)",
          &o->batch);
  t->Flag("--streaming",
          "openseqslam: the causal engine, trailing window (implies --matcher "
          "openseqslam)",
          &o->streaming);
  t->Int("--max-advance", "K", "filter: route rows per frame at most (default 8)", 1,
         dsp::kMaxAdvance, &o->max_advance);
  t->Number("--keyframe-noise", "F",
            "filter: keyframe merge threshold x noise floor (default 2; 0 keeps every "
            "reference frame)",
            {0, 100}, &o->keyframe_noise_factor);
  t->Text("--config", "FILE",
          "the firmware configuration whose [state], [seqslam] and [descriptor] the runs use "
          "(default: the built-in ones)",
          &o->config_file);
  t->Text("--gt", "FILE", "ground truth CSV: query_index,reference_index (-1: off route)",
          &o->gt_file);
  t->Number("--tolerance-m", "X",
            "ground truth from the datasets' poses: a match is correct when the matched "
            "reference was recorded within X m of the query",
            kPositive, &o->tolerance_m);
  t->Int("--frame-tolerance", "N",
         "with --gt or pose-derived truth: correct within +-N frames (default 5, as the paper)", 0,
         std::numeric_limits<int>::max(), &o->frame_tolerance);
  t->Text("--camera", "FILE.toml",
          "sky: the camera file for both runs (default: each dataset's camera.toml, else a "
          "lens guessed from the image's shape)",
          &o->describe.camera);
  t->Custom("--lens", "MODEL",
            "sky: override the lens model (equidistant, equisolid or "
            "equirectangular; other models need a camera file)",
            [o](const char* text, std::string* expected) {
              dsp::LensModel model;
              if (!dsp::ParseLensModel(text, &model) || model == dsp::LensModel::kKannalaBrandt ||
                  model == dsp::LensModel::kOCamCalib || model == dsp::LensModel::kPinhole) {
                *expected = "equidistant, equisolid or equirectangular";
                return false;
              }
              o->describe.lens = model;
              return true;
            });
  t->Number("--fov", "DEG", "sky: override the field of view, degrees", {0, 360, true, false},
            &o->describe.fov_deg);
  static_assert(firmware::DescriptorConfig{}.bands == 120, "the help states the default bands");
  t->Int("--bands", "N",
         "sky: spherical-harmonic bands on the configuration's grid (default: [descriptor] "
         "bands, 120)",
         1, 512, &o->bands);
  t->Int("--jobs", "N",
         "threads for the descriptors and the batch matcher (default: all "
         "cores); the results do not depend on it",
         1, 1024, &o->describe.jobs);
  t->Choice("--vanilla-precision",
            "vanilla in the batch matcher: 8 bits a value (default; as accurate, "
            "docs/SEQSLAM.md) or floats",
            {{"byte", true}, {"float", false}}, &o->vanilla_bytes);
  t->Choice("--attitude",
            "sky: dataset describes the sky above the gravity-aligned cap, each frame levelled "
            "by its recorded roll and pitch (default none)",
            {{"none", false}, {"dataset", true}}, &o->describe.attitude_from_dataset);
  t->Number("--max-tilt", "DEG",
            "with --attitude dataset: the largest tilt the cap must survive (default: "
            "[attitude] max_tilt_deg of --config)",
            {0, 80}, &o->describe.max_tilt_deg);
}

// Parses and checks the command line; kRun or the outcome to exit with.
ParseOutcome ParseArgs(std::span<char* const> args, EvalOptions* o) {
  o->describe.jobs = tools::DefaultJobs();  // --jobs replaces it
  OptionTable t("eval", "--reference DIR --query DIR --out DIR [options]", kDescription);
  AddOptions(&t, o);
  if (const ParseOutcome p = t.Parse(args); p != ParseOutcome::kRun)
    return p;
  if (o->reference.empty() || o->query.empty() || o->out.empty())
    return t.Refuse("--reference, --query and --out are required");
  if (o->batch && o->streaming)
    return t.Refuse("--batch and --streaming exclude each other");
  if (!o->gt_file.empty() && o->tolerance_m > 0)
    return t.Refuse("--gt and --tolerance-m exclude each other");
  const auto asked = [o](ScoredDescriptor d) {
    return std::find(o->methods.begin(), o->methods.end(), d) != o->methods.end();
  };
  if (asked(ScoredDescriptor::kFabmap) && o->vocab.empty())
    return t.Refuse("--method fabmap needs --vocab FILE (write one with skyloc fabmap-train)");
  if (o->describe.max_tilt_deg && !o->describe.attitude_from_dataset)
    return t.Refuse("--max-tilt sets the gravity-aligned cap: add --attitude dataset");
  if (o->methods.empty()) {
    o->methods = {ScoredDescriptor::kSky, ScoredDescriptor::kVanilla};
    if (!o->vocab.empty())
      o->methods.push_back(ScoredDescriptor::kFabmap);
  }
  const bool openseqslam_window = o->batch || o->streaming;
  if (o->matchers.empty()) {
    o->matchers = {openseqslam_window ? Matcher::kOpenSeqSlam : Matcher::kRouteFilter};
  } else if (openseqslam_window && std::find(o->matchers.begin(), o->matchers.end(),
                                             Matcher::kOpenSeqSlam) == o->matchers.end()) {
    return t.Refuse(
        "--batch and --streaming choose openseqslam's window: add --matcher openseqslam");
  }
  std::sort(o->matchers.begin(), o->matchers.end());
  o->matchers.erase(std::unique(o->matchers.begin(), o->matchers.end()), o->matchers.end());
  if (o->ds_list.empty())
    o->ds_list = {1, 10, 20};
  std::sort(o->methods.begin(), o->methods.end());
  o->methods.erase(std::unique(o->methods.begin(), o->methods.end()), o->methods.end());
  return ParseOutcome::kRun;
}

// --config, then the flags that override it.
Status ApplyConfig(EvalOptions* o) {
  Config& config = o->describe.config;
  if (!o->config_file.empty()) {
    SKYLOC_TRY_ASSIGN(config, firmware::LoadConfigFile(o->config_file.c_str()));
  }
  if (o->max_advance)
    config.seqslam.filter.max_advance = *o->max_advance;
  if (o->keyframe_noise_factor)
    config.seqslam.filter.keyframe_noise_factor = static_cast<float>(*o->keyframe_noise_factor);
  if (o->bands) {
    if (config.descriptor.grid == firmware::GridPreset::kPaper)
      return Status::Error(StatusCode::kInvalidArgument,
                           "--bands %d: the configuration's [descriptor] grid = \"paper\" has 120 "
                           "bands; leave --bands out or choose another grid",
                           *o->bands);
    config.descriptor.bands = *o->bands;
    firmware::ResolveDescriptorGrid(&config.descriptor);  // a custom grid stays as it was
  }
  return Status::Ok();
}

std::vector<dsp::Position3> PositionsOf(const drivers::Dataset& d) {
  std::vector<dsp::Position3> xyz;
  for (const drivers::DatasetFrame& f : d.frames)
    xyz.push_back({f.pose->x_m, f.pose->y_m, f.pose->z_m});
  return xyz;
}

Result<GroundTruth> MakeGroundTruth(const EvalOptions& o, const drivers::Dataset& ref,
                                    const drivers::Dataset& query) {
  dsp::MatchTolerance tolerance;
  tolerance.frames = o.frame_tolerance;
  if (!o.gt_file.empty())
    return tools::ReadGroundTruthCsv(o.gt_file, static_cast<int>(query.frames.size()),
                                     static_cast<int>(ref.frames.size()), tolerance);
  if (!ref.has_poses || !query.has_poses) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "no ground truth: %s has no poses in frames.csv; pass --gt FILE "
                         "(query_index,reference_index)",
                         ref.has_poses ? query.dir.c_str() : ref.dir.c_str());
  }
  // With a distance tolerance, a query farther than it from the whole route is off it.
  const bool by_distance = o.tolerance_m > 0;
  tolerance.metres = by_distance ? o.tolerance_m : 0;
  GroundTruth gt = tools::GroundTruthFromPositions(
      PositionsOf(ref), PositionsOf(query),
      by_distance ? o.tolerance_m : std::numeric_limits<double>::infinity(), tolerance);
  gt.description = by_distance
                       ? tools::Format("poses, correct within %.3g m", o.tolerance_m)
                       : tools::Format("poses (nearest reference frames), correct within %d frames",
                                       o.frame_tolerance);
  return gt;
}

// --out must be new or empty unless --force: an earlier evaluation is not replaced
// silently. Checked before any work is done.
Status CheckOutFolder(const EvalOptions& o) {
  std::error_code ec;
  const std::filesystem::file_status st = std::filesystem::status(o.out, ec);
  if (ec || !std::filesystem::exists(st) || !std::filesystem::is_directory(st) || o.force)
    return Status::Ok();  // new, or not a folder: creating it reports that
  std::filesystem::directory_iterator it(o.out, ec);
  if (ec) {
    return Status::Error(StatusCode::kUnavailable, "cannot read output folder %s: %s",
                         o.out.c_str(), ec.message().c_str());
  }
  if (it == std::filesystem::directory_iterator())
    return Status::Ok();
  return Status::Error(StatusCode::kFailedPrecondition,
                       "--out %s is not empty (it holds %s): pass --force to replace its "
                       "results, or give a new or empty folder",
                       o.out.c_str(), it->path().filename().c_str());
}

// What every run of one evaluation reads.
struct Evaluation {
  const EvalOptions& o;
  drivers::Dataset ref, query;
  GroundTruth gt;
  std::vector<double> ref_yaw, query_yaw;  // empty without poses
  // The sky descriptors and their strips, computed once for the sky method and surf1d
  // (which reads only the strips: without sky, no floats are kept).
  std::optional<RunDescription> sky_ref, sky_query;
  std::vector<EvalRun> runs;

  const Config& config() const { return o.describe.config; }
  Status DescribeSky();
  Status AddMatcherRuns(ScoredDescriptor method, const RunDescription& rd,
                        const RunDescription& qd);
  Status AddSurf1dRuns();
  Status AddFabmapRun();
};

Status Evaluation::DescribeSky() {
  if (sky_ref.has_value())
    return Status::Ok();
  std::fprintf(stderr, "skyloc eval: sky descriptors of %zu + %zu frames...\n", ref.frames.size(),
               query.frames.size());
  tools::DescribeSettings settings = o.describe;
  settings.floats =
      std::find(o.methods.begin(), o.methods.end(), ScoredDescriptor::kSky) != o.methods.end();
  SKYLOC_TRY_ASSIGN(RunDescription rd,
                    tools::DescribeDataset(ScoredDescriptor::kSky, o.reference, settings));
  SKYLOC_TRY_ASSIGN(RunDescription qd,
                    tools::DescribeDataset(ScoredDescriptor::kSky, o.query, settings));
  sky_ref = std::move(rd);
  sky_query = std::move(qd);
  return Status::Ok();
}

// Every matcher at every --ds over one descriptor, with the heading of the correctly
// matched frames and landmark confirmation where the runs have strips.
Status Evaluation::AddMatcherRuns(ScoredDescriptor method, const RunDescription& rd,
                                  const RunDescription& qd) {
  for (const Matcher matcher : o.matchers) {
    for (const int ds : o.ds_list) {
      EvalRun run;
      run.descriptor = method;
      run.matcher = matcher;
      run.matcher_name = firmware::NameOf(matcher);
      run.ds = ds;
      run.matches.assign(static_cast<std::size_t>(qd.count), dsp::SeqSlamMatch{});
      const std::string progress = tools::Format("%s %s ds %d", tools::ScoredDescriptorName(method),
                                                 run.matcher_name.c_str(), ds);
      tools::MatcherSettings settings;
      settings.matcher = matcher;
      settings.filter = config().seqslam.filter;
      settings.storage = config().capacities.route_storage;
      settings.filter.sequence_length = ds;
      settings.openseqslam = dsp::SeqSlamParams{};
      settings.openseqslam.sequence_length = ds;
      settings.streaming = o.streaming;
      settings.jobs = o.describe.jobs;
      settings.progress = progress.c_str();
      SKYLOC_TRY(tools::MatchRows(rd.rows(), qd.rows(), settings, run.matches));
      tools::ScoreRun(config(), gt, &run);
      const bool strips = rd.strip_columns > 0 && rd.strip_columns == qd.strip_columns;
      if (strips && !ref_yaw.empty()) {
        SKYLOC_TRY_ASSIGN(run.heading, tools::EvaluateHeadings(config().heading.estimate,
                                                               rd.horizon(), qd.horizon(), ref_yaw,
                                                               query_yaw, run.matches, run.scored));
        run.heading_evaluated = true;
      }
      SKYLOC_TRY_ASSIGN(run.confirmation,
                        tools::LandmarkConfirmation(config(), matcher, rd.horizon(), qd.horizon(),
                                                    gt, run.matches, run.scored));
      runs.push_back(std::move(run));
    }
  }
  return Status::Ok();
}

// `--method surf1d`: one run "single" (each query's best-scoring reference frame) and one
// OpenSeqSLAM run per --ds over the differences best - score (SeqSLAM's local contrast
// enhancement normalises each column, so only the order and spread of a query's scores
// matter). It reads the sky method's horizon strips.
Status Evaluation::AddSurf1dRuns() {
  if (!config().heading.enabled())
    return Status::Error(StatusCode::kInvalidArgument,
                         "--method surf1d needs horizon strips: [heading] strip_columns is 0 "
                         "in --config; set it (default 360)");
  SKYLOC_TRY(DescribeSky());
  const RunDescription& rd = *sky_ref;
  const RunDescription& qd = *sky_query;
  if (rd.strip_columns == 0 || rd.strip_columns != qd.strip_columns)
    return Status::Error(StatusCode::kInvalidArgument,
                         "--method surf1d: the lens does not see the [heading] band in both "
                         "datasets (see the message above); set the band or the camera file");
  SKYLOC_TRY_ASSIGN(const std::vector<float> scores,
                    tools::Surf1dScores(rd.strips, qd.strips, rd.strip_columns,
                                        config().heading.estimate, o.describe.jobs));
  const auto n_ref = static_cast<std::size_t>(rd.count);
  const auto n_query = static_cast<std::size_t>(qd.count);
  EvalRun single;
  single.descriptor = ScoredDescriptor::kSurf1d;
  single.matcher = Matcher::kOpenSeqSlam;
  single.matcher_name = "single";
  single.ds = 1;
  single.matches.resize(n_query);
  std::vector<float> differences(scores.size());
  for (std::size_t q = 0; q < n_query; ++q) {
    const std::span<const float> column = std::span(scores).subspan(q * n_ref, n_ref);
    single.matches[q] = tools::BestScore(column, config().seqslam.rwindow());
    const float best = *std::max_element(column.begin(), column.end());
    for (std::size_t r = 0; r < n_ref; ++r)
      differences[q * n_ref + r] = best - column[r];
  }
  tools::ScoreRun(config(), gt, &single);
  runs.push_back(std::move(single));
  for (const int ds : o.ds_list) {
    EvalRun run;
    run.descriptor = ScoredDescriptor::kSurf1d;
    run.matcher = Matcher::kOpenSeqSlam;
    run.matcher_name = firmware::NameOf(Matcher::kOpenSeqSlam);
    run.ds = ds;
    run.matches.resize(n_query);
    dsp::SeqSlamParams p;
    p.sequence_length = ds;
    if (const dsp::SeqSlamError e = dsp::SeqSlamFromDifferences(
            differences, rd.count, qd.count, p, dsp::SeqSlamWindow::kCentred, run.matches);
        e != dsp::SeqSlamError::kOk)
      return drivers::DspStatus(e, "surf1d openseqslam ds %d", ds);
    tools::ScoreRun(config(), gt, &run);
    runs.push_back(std::move(run));
  }
  return Status::Ok();
}

// FAB-MAP 2.0: one run, no sequence; the state machine as [seqslam] matcher of --config.
Status Evaluation::AddFabmapRun() {
  std::fprintf(stderr, "skyloc eval: fabmap: SIFT words of both runs (vocabulary %s)...\n",
               o.vocab.c_str());
  tools::FabmapEvalTiming timing;
  SKYLOC_TRY_ASSIGN(
      const std::vector<tools::FabmapQueryMatch> found,
      tools::MatchWithFabmap(o.vocab, o.reference, o.query, tools::FabMapParams{}, &timing));
  std::fprintf(stderr,
               "skyloc eval: fabmap: features %.2f s, inference %.3f ms per query over %d "
               "places\n",
               timing.features_s,
               timing.queries > 0 ? 1e3 * timing.inference_s / timing.queries : 0.0, timing.places);
  EvalRun run;
  run.descriptor = ScoredDescriptor::kFabmap;
  run.matcher = config().seqslam.matcher;
  run.matcher_name = "fabmap2";
  run.ds = 1;
  run.matches = tools::FabmapMatches(found);
  tools::ScoreRun(config(), gt, &run);
  runs.push_back(std::move(run));
  return Status::Ok();
}

// The vanilla descriptors of both runs, in the forms the matchers read: bytes only for
// OpenSeqSLAM's batch engine (--vanilla-precision byte); the route filter and the
// streaming engine read floats.
Status DescribeVanilla(const EvalOptions& o, std::optional<RunDescription>* rd,
                       std::optional<RunDescription>* qd, std::size_t n_ref, std::size_t n_query) {
  std::fprintf(stderr, "skyloc eval: vanilla descriptors of %zu + %zu frames...\n", n_ref, n_query);
  const bool batch_openseqslam =
      !o.streaming &&
      std::find(o.matchers.begin(), o.matchers.end(), Matcher::kOpenSeqSlam) != o.matchers.end();
  tools::DescribeSettings settings = o.describe;
  settings.bytes = o.vanilla_bytes && batch_openseqslam;
  settings.floats = !settings.bytes || o.matchers.size() > 1 || !batch_openseqslam;
  SKYLOC_TRY_ASSIGN(*rd, tools::DescribeDataset(ScoredDescriptor::kVanilla, o.reference, settings));
  SKYLOC_TRY_ASSIGN(*qd, tools::DescribeDataset(ScoredDescriptor::kVanilla, o.query, settings));
  return Status::Ok();
}

void PrintSummary(const EvalOptions& o, const GroundTruth& gt, const std::vector<EvalRun>& runs) {
  std::printf("%-8s %-12s %4s %9s %8s %13s %13s %7s %18s\n", "method", "matcher", "ds", "evaluated",
              "correct", "P@100%recall", "R@100%prec", "AUC", "LOCALISED correct");
  for (const EvalRun& r : runs) {
    const dsp::PrSummary& s = r.scored.pr.summary;
    std::printf("%-8s %-12s %4d %9d %8d %13.3f %13.3f %7.3f %8d of %6d\n",
                tools::ScoredDescriptorName(r.descriptor), r.matcher_name.c_str(), r.ds,
                s.evaluated, s.correct, s.precision_at_full_recall, s.recall_at_full_precision,
                s.area_under_curve, r.localised.correct, r.localised.localised);
  }
  for (const EvalRun& r : runs) {
    if (!r.heading_evaluated)
      continue;
    const dsp::HeadingErrorSummary& c = r.heading.correlation;
    const dsp::HeadingErrorSummary& s = r.heading.surf;
    std::printf(
        "heading %s %s ds %d, %d correctly matched frames: cross-correlation median %.2f, p90 "
        "%.2f deg (%d estimated); 1D SURF median %.2f, p90 %.2f deg (%d estimated)\n",
        tools::ScoredDescriptorName(r.descriptor), r.matcher_name.c_str(), r.ds, c.frames,
        c.median_deg, c.p90_deg, c.estimated, s.median_deg, s.p90_deg, s.estimated);
  }
  for (const EvalRun& r : runs) {
    if (r.confirmation.empty())
      continue;
    std::printf("landmark confirmation %s %s ds %d: LOCALISED correct %d of %d without;",
                tools::ScoredDescriptorName(r.descriptor), r.matcher_name.c_str(), r.ds,
                r.localised.correct, r.localised.localised);
    for (const tools::Confirmation& c : r.confirmation)
      std::printf(" score >= %.0f: %d of %d;", c.min_score, c.count.correct, c.count.localised);
    std::printf("\n");
  }
  const bool openseqslam =
      std::find(o.matchers.begin(), o.matchers.end(), Matcher::kOpenSeqSlam) != o.matchers.end();
  std::printf("ground truth: %s;%s results in %s\n", gt.description.c_str(),
              openseqslam ? (o.streaming ? " openseqslam streaming;" : " openseqslam batch;") : "",
              o.out.c_str());
}

Status WriteResults(const Evaluation& e) {
  const EvalOptions& o = e.o;
  const int n_ref = static_cast<int>(e.ref.frames.size());
  tools::EvalMetricsHeader header;
  header.reference = o.reference;
  header.query = o.query;
  header.reference_frames = n_ref;
  header.query_frames = static_cast<int>(e.query.frames.size());
  header.streaming = o.streaming;
  header.vanilla_bytes = o.vanilla_bytes;
  header.ground_truth = e.gt.description;
  header.frame_tolerance = o.frame_tolerance;
  SKYLOC_TRY(tools::WriteMatchesCsv(o.out + "/matches.csv", e.runs));
  SKYLOC_TRY(tools::WriteEvalMetricsJson(o.out + "/metrics.json", header, e.runs));
  SKYLOC_TRY(tools::WriteText(o.out + "/pr.svg", tools::EvalPrPlot(e.runs)));
  return tools::WriteText(o.out + "/correspondence.svg",
                          tools::EvalCorrespondencePlot(e.runs, e.gt, n_ref));
}

Status Evaluate(EvalOptions o) {
  SKYLOC_TRY(ApplyConfig(&o));
  SKYLOC_TRY_ASSIGN(drivers::Dataset ref, drivers::ReadDataset(o.reference));
  SKYLOC_TRY_ASSIGN(drivers::Dataset query, drivers::ReadDataset(o.query));
  SKYLOC_TRY_ASSIGN(GroundTruth gt, MakeGroundTruth(o, ref, query));
  // A query without truth is scored in nothing: scores over a few of them say little, so
  // the coverage is told whenever it is not whole (a warning below half).
  const auto covered = static_cast<std::size_t>(std::count_if(
      gt.truth.begin(), gt.truth.end(), [](const dsp::TruthInterval& t) { return t.has_truth(); }));
  if (covered < gt.truth.size())
    std::fprintf(stderr,
                 "skyloc eval: %s: the ground truth (%s) covers %zu of %zu query frames; the "
                 "others are in no score\n",
                 2 * covered < gt.truth.size() ? "warning" : "note", gt.description.c_str(),
                 covered, gt.truth.size());
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) {
    return Status::Error(StatusCode::kUnavailable, "cannot create output folder %s: %s",
                         o.out.c_str(), ec.message().c_str());
  }
  Evaluation e{o, std::move(ref), std::move(query), std::move(gt), {}, {}, {}, {}, {}};
  if (e.ref.has_poses && e.query.has_poses) {
    for (const drivers::DatasetFrame& f : e.ref.frames)
      e.ref_yaw.push_back(f.pose->yaw_deg);
    for (const drivers::DatasetFrame& f : e.query.frames)
      e.query_yaw.push_back(f.pose->yaw_deg);
  }
  for (const ScoredDescriptor method : o.methods) {
    if (method == ScoredDescriptor::kSurf1d) {
      SKYLOC_TRY(e.AddSurf1dRuns());
    } else if (method == ScoredDescriptor::kFabmap) {
      SKYLOC_TRY(e.AddFabmapRun());
    } else if (method == ScoredDescriptor::kSky) {
      SKYLOC_TRY(e.DescribeSky());
      SKYLOC_TRY(e.AddMatcherRuns(method, *e.sky_ref, *e.sky_query));
    } else {
      std::optional<RunDescription> rd, qd;
      SKYLOC_TRY(DescribeVanilla(o, &rd, &qd, e.ref.frames.size(), e.query.frames.size()));
      SKYLOC_TRY(e.AddMatcherRuns(method, *rd, *qd));
    }
  }
  SKYLOC_TRY(WriteResults(e));
  PrintSummary(o, e.gt, e.runs);
  return Status::Ok();
}

int EvaluateRuns(const EvalOptions& options) {
  // A file past RLIMIT_FSIZE is then a write error (EFBIG) reported naming the file, not a
  // silent death by signal.
  std::signal(SIGXFSZ, SIG_IGN);
  if (const Status out = CheckOutFolder(options); !out.ok()) {
    std::fprintf(stderr, "skyloc eval: %s\n", out.message());
    return kExitUsage;
  }
  const Status s = Evaluate(options);
  if (!s.ok())
    return Failed("eval", s);
  return kExitOk;
}

}  // namespace

int RunEval(std::span<char* const> args) {
  return RunParsed(args, ParseArgs, EvaluateRuns);
}

}  // namespace skyloc::cli
