// `skyloc experiment surf1d --out DIR`: the 1D SURF paper's classification experiment on
// the simulated city (sim/surf1d_experiment.h; docs/SURF1D.md, "The paper's experiment").
// Writes DIR/results.md (the AUCs beside the paper's and the command), DIR/metrics.json
// and DIR/roc.svg (the paper's Fig. 4).
#include <sys/stat.h>

#include <cerrno>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "cli/commands.h"
#include "cli/options.h"
#include "tools/output_file.h"
#include "tools/surf1d_experiment.h"
#include "tools/svg_plot.h"

namespace skyloc::cli {
using namespace skyloc::tools;
namespace {

constexpr const char* kDescription =
    "The 1D SURF paper's classification experiment (Anderson et al. 2012, section 4.1) in\n"
    "the simulated city: the robot turns on the spot at each place taking N images evenly\n"
    "over 360 degrees; every pair at a place is scored by 1D SURF (NN, NN with RANSAC).\n"
    "Forward pinhole camera (the paper's 47.8 degrees): a pair matches when its headings\n"
    "differ by less than 20 degrees. Upward fisheye, 360-degree strip: a pair matches when\n"
    "it is at the same place (the other place's images are the non-matches).\n"
    "Writes DIR/results.md, DIR/metrics.json and DIR/roc.svg.\n";

void PrintProgress(const char* what) {
  std::fprintf(stderr, "skyloc experiment surf1d: %s\n", what);
}

// The curve with its points at least `step` apart (either axis), ends kept: thousands of
// pairs give thousands of points, far more than a plot or a file needs (the AUCs are
// computed on the full curves).
std::vector<dsp::RocPoint> Thinned(const std::vector<dsp::RocPoint>& roc, double step = 0.002) {
  std::vector<dsp::RocPoint> out;
  for (std::size_t i = 0; i < roc.size(); ++i) {
    if (i == 0 || i + 1 == roc.size() ||
        std::fabs(roc[i].false_positive_rate - out.back().false_positive_rate) >= step ||
        std::fabs(roc[i].true_positive_rate - out.back().true_positive_rate) >= step)
      out.push_back(roc[i]);
  }
  return out;
}

std::string RocJson(const std::vector<dsp::RocPoint>& full) {
  const std::vector<dsp::RocPoint> roc = Thinned(full);
  std::string s = "[";
  for (std::size_t i = 0; i < roc.size(); ++i)
    s += Format("%s[%.5f, %.5f]", i ? ", " : "", roc[i].false_positive_rate,
                roc[i].true_positive_rate);
  return s + "]";
}

std::string CameraJson(const char* key, const tools::Surf1dCameraResult& r) {
  return Format(
             "  \"%s\": {\"camera\": \"%s\", \"strip_columns\": %d, \"mean_features\": %.1f, "
             "\"matched_pairs\": %d, \"unmatched_pairs\": %d, \"auc_nn\": %.4f, "
             "\"auc_ransac\": %.4f,\n",
             key, r.camera.c_str(), r.strip_columns, r.mean_features, r.matched_pairs,
             r.unmatched_pairs, r.auc_nn, r.auc_ransac) +
         "    \"roc_nn_thinned\": " + RocJson(r.roc_nn) +
         ",\n    \"roc_ransac_thinned\": " + RocJson(r.roc_ransac) + "}";
}

// The experiment's command line; the words after "skyloc experiment" (args[0] "surf1d")
// go into results.md as they were given.
struct Surf1dExperimentArgs {
  tools::Surf1dExperimentOptions experiment;
  std::string out;
  std::string command = "skyloc experiment";
};

ParseOutcome ParseArgs(std::span<char* const> args, Surf1dExperimentArgs* options) {
  for (char* const a : args)
    options->command += std::string(" ") + a;
  tools::Surf1dExperimentOptions& o = options->experiment;
  std::int64_t seed = 0;
  OptionTable t("experiment surf1d", "--out DIR [options]", kDescription);
  t.Text("--out", "DIR", "where to write results.md, metrics.json, roc.svg (required)",
         &options->out);
  t.Int("--images", "N", "images a place (default 88, the paper's)", 8, 1000, &o.images_per_place);
  t.Int("--places", "N", "places along the city route (default 2)", 2, 50, &o.places);
  t.Int("--width", "W", "forward camera width (default 640)", 64, 4096, &o.width);
  t.Int("--height", "H", "forward camera height (default 480)", 16, 4096, &o.height);
  t.Int("--fisheye-width", "W", "upward camera width (default 640)", 16, 4096, &o.fisheye_width);
  t.Int("--fisheye-height", "H", "upward camera height (default 480)", 16, 4096, &o.fisheye_height);
  t.Number("--pitch", "DEG", "forward camera pitch, nose up positive (default -5)", {-20, 20},
           &o.pitch_deg);
  t.Int("--seed", "N", "city seed (default 1)", 0, 1000000000, &seed);
  // args[0] is "surf1d", the experiment's name.
  if (const ParseOutcome outcome = t.Parse(args.subspan(1)); outcome != ParseOutcome::kRun)
    return outcome;
  if (t.Given("--seed"))
    o.world_seed = static_cast<std::uint64_t>(seed);
  if (options->out.empty())
    return t.Refuse("--out DIR is required (where to write results.md, metrics.json, roc.svg)");
  return ParseOutcome::kRun;
}

int RunAndWrite(const Surf1dExperimentArgs& options) {
  const tools::Surf1dExperimentOptions& o = options.experiment;
  const std::string& out = options.out;
  const std::string& command = options.command;
  tools::Surf1dCameraResult forward, fisheye;
  if (Status s = tools::RunSurf1dExperiment(o, &forward, &fisheye, PrintProgress); !s.ok()) {
    return Failed("experiment surf1d", s);
  }
  std::string md = "# skyloc experiment surf1d\n\n```\n" + command +
                   "\n```\n\n| camera | strip columns | features / image | matched / unmatched "
                   "pairs | AUC NN | AUC NN with RANSAC |\n|---|---|---|---|---|---|\n";
  md +=
      "| paper: Nao forward camera, office (Table 1) | 160 | 59.2 | 480 / 2065 | 88.0 % | "
      "89.6 % |\n";
  for (const tools::Surf1dCameraResult* r : {&forward, &fisheye})
    md += Format("| %s | %d | %.1f | %d / %d | %.1f %% | %.1f %% |\n", r->camera.c_str(),
                 r->strip_columns, r->mean_features, r->matched_pairs, r->unmatched_pairs,
                 100 * r->auc_nn, 100 * r->auc_ransac);
  md += Format(
      "\nForward camera with only the non-matching pairs that share no view (headings at "
      "least %.3g degrees apart, %d pairs): AUC NN %.1f %%, NN with RANSAC %.1f %%.\n",
      o.fov_deg, forward.disjoint_pairs, 100 * forward.auc_nn_disjoint,
      100 * forward.auc_ransac_disjoint);
  md += Format(
      "\n%d images a place, %d places along the city route (seed %llu), camera %.2g m up. "
      "Forward: pitch %.3g degrees with +-%.3g degrees of random roll and pitch per image, "
      "the horizon row from the true attitude, every %d columns, a %d-row band; a pair "
      "matches when its headings differ by less than %.3g degrees, pairs at one place only. "
      "Fisheye: level, dsp::HorizonStrip's %d columns over %.3g..%.3g degrees of elevation; a "
      "pair matches when it is at the same place. ROC: roc.svg.\n",
      o.images_per_place, o.places, static_cast<unsigned long long>(o.world_seed),
      o.camera_height_m, o.pitch_deg, o.attitude_jitter_deg, o.column_step, o.band_rows,
      o.match_below_deg, o.fisheye_strip.n_azimuth, o.fisheye_strip.elevation_min_deg,
      o.fisheye_strip.elevation_max_deg);
  const std::string json =
      "{\n  \"experiment\": \"surf1d\",\n  \"command\": \"" + command +
      "\",\n  \"paper\": {\"auc_nn\": 0.880, \"auc_ransac\": 0.896},\n" +
      CameraJson("forward", forward) + ",\n" +
      Format(
          "  \"forward_disjoint\": {\"unmatched_pairs\": %d, \"auc_nn\": "
          "%.4f, \"auc_ransac\": %.4f},\n",
          forward.disjoint_pairs, forward.auc_nn_disjoint, forward.auc_ransac_disjoint) +
      CameraJson("fisheye", fisheye) + "\n}\n";
  const std::vector<RocCurveLine> curves = {
      {"forward pinhole, NN: AUC " + Format("%.3f", forward.auc_nn), Thinned(forward.roc_nn),
       LineDash::kDashed},
      {"forward pinhole, NN with RANSAC: AUC " + Format("%.3f", forward.auc_ransac),
       Thinned(forward.roc_ransac), LineDash::kSolid},
      {"upward fisheye 360, NN: AUC " + Format("%.3f", fisheye.auc_nn), Thinned(fisheye.roc_nn),
       LineDash::kDashed},
      {"upward fisheye 360, NN with RANSAC: AUC " + Format("%.3f", fisheye.auc_ransac),
       Thinned(fisheye.roc_ransac), LineDash::kSolid}};
  const std::string svg = RocPlotSvg("1D SURF recognition score, simulated city", curves);
  if (::mkdir(out.c_str(), 0755) != 0 && errno != EEXIST) {
    std::fprintf(stderr, "skyloc experiment surf1d: cannot create '%s': %s\n", out.c_str(),
                 std::strerror(errno));
    return kExitFailure;
  }
  using Output = std::pair<const char*, const std::string*>;
  for (const auto& [name, text] :
       {Output{"/results.md", &md}, Output{"/metrics.json", &json}, Output{"/roc.svg", &svg}}) {
    if (Status s = WriteText(out + name, *text); !s.ok()) {
      return Failed("experiment surf1d", s);
    }
  }
  std::fputs(md.c_str(), stdout);
  std::printf("skyloc experiment surf1d: wrote %s/: results.md, metrics.json, roc.svg\n",
              out.c_str());
  return kExitOk;
}

}  // namespace

int RunSurf1dExperiment(std::span<char* const> args) {
  return RunParsed(args, ParseArgs, RunAndWrite);
}

}  // namespace skyloc::cli
