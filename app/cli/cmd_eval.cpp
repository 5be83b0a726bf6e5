// `skyloc eval`: place recognition of a query run against a reference run (two dataset
// folders), with SeqSLAM over the sky descriptor and/or the vanilla (patch-normalised
// greyscale) descriptor, at one or more sequence lengths, and FAB-MAP 2.0 (SIFT words, a
// vocabulary from `skyloc fabmap-train`; host builds only, docs/FABMAP.md). Writes matches.csv,
// metrics.json, pr.svg and correspondence.svg into --out (docs/SEQSLAM.md, "Evaluation").
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <limits>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include "cli/commands.h"
#include "cli/eval_descriptor.h"
#include "firmware/config.h"
#include "firmware/descriptor.h"
#include "firmware/pipeline.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dataset.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/localisation_state.h"
#include "skyloc/dsp/place_metrics.h"
#include "skyloc/dsp/route_filter.h"
#include "skyloc/dsp/seqslam.h"
#include "skyloc/dsp/seqslam_batch.h"
#include "skyloc/dsp/sky_descriptor.h"
#include "skyloc/dsp/surf1d.h"
#include "skyloc/dsp/vanilla_descriptor.h"
#include "skyloc/platform/status.h"
#include "tools/fabmap_eval.h"
#include "tools/output_file.h"
#include "tools/parallel.h"
#include "tools/progress.h"
#include "tools/svg_plot.h"

namespace skyloc::cli {
using namespace skyloc::firmware;
using namespace skyloc::tools;
namespace {

constexpr const char* kUsage =
    "usage: skyloc eval --reference DIR --query DIR --out DIR [options]\n"
    "\n"
    "Matches every query frame against the reference route and scores the matches\n"
    "against the ground truth. DIRs are dataset folders (docs/DATASETS.md).\n"
    "\n"
    "  --method sky|vanilla|fabmap|surf1d  descriptor (repeat to compare; default: sky\n"
    "                         and vanilla, and fabmap too when --vocab is given). fabmap is\n"
    "                         FAB-MAP 2.0 on SIFT words (docs/FABMAP.md): one run, no\n"
    "                         matcher or sequence length; host builds only. surf1d is\n"
    "                         the 1D SURF recognition score (NN with RANSAC) of the\n"
    "                         [heading] strips (the sky lens): \"single\" (each query's\n"
    "                         best-scoring frame) and OpenSeqSLAM over the scores\n"
    "                         (difference = the query's best score - score) at each --ds;\n"
    "                         every query against every frame: slow on long routes\n"
    "  --vocab FILE           fabmap: the vocabulary from skyloc fabmap-train\n"
    "  --matcher filter|openseqslam  the matcher (repeat to compare; default: filter, the\n"
    "                         firmware's route filter; docs/SEQSLAM.md)\n"
    "  --ds N                 sequence length in frames (repeat; default: 1 10 20)\n"
    "  --batch                openseqslam: OpenSeqSLAM's centred window (default)\n"
    "  --streaming            openseqslam: the causal engine (trailing window)\n"
    "                         (either alone implies --matcher openseqslam)\n"
    "  --max-advance K        filter: route rows per frame at most (default 8)\n"
    "  --keyframe-noise F     filter: keyframe merge threshold x noise floor (default 2)\n"
    "  --config FILE          the firmware configuration whose [state] settings (and\n"
    "                         [seqslam] max_advance, keyframe_noise_factor, [descriptor]\n"
    "                         bands, grid, normalisation) the runs use (default: the\n"
    "                         built-in defaults; normalisation unit_l2, \"none\" is the\n"
    "                         paper's eq. 3)\n"
    "  --gt FILE              ground truth CSV: query_index,reference_index (-1: off route)\n"
    "  --tolerance-m X        ground truth from the datasets' poses: a match is correct when\n"
    "                         the matched reference was recorded within X m of the query\n"
    "  --frame-tolerance N    with --gt or pose-derived truth: correct within +-N frames\n"
    "                         (default 5, as the paper)\n"
    "  --camera FILE.toml     sky: the camera file (docs/CAMERA_FILE.md) for both runs;\n"
    "                         otherwise each dataset's camera.toml, otherwise an\n"
    "                         equidistant 185-degree lens filling the short image side\n"
    "                         (equirectangular for 2:1 images), as skyloc describe\n"
    "  --lens MODEL, --fov DEG  sky: override the lens model / field of view\n"
    "  --bands N              sky: spherical-harmonic bands, on the configuration's grid\n"
    "                         (default: [descriptor] of --config, as the firmware: 64\n"
    "                         bands on the oversampled 48 x 256 grid)\n"
    "  --jobs N               threads for the descriptors and the batch matcher (default:\n"
    "                         all cores); the results do not depend on it\n"
    "  --vanilla-precision byte|float  vanilla with the batch matcher: the descriptor in\n"
    "                         8 bits (steps of 1/16 of a patch's std, summed with SSE2/NEON\n"
    "                         byte instructions; as accurate, measured: docs/SEQSLAM.md)\n"
    "                         or as floats (default byte)\n"
    "  --attitude none|dataset  sky: dataset describes the sky above the gravity-aligned\n"
    "                         cap, each frame levelled by the roll and pitch recorded\n"
    "                         with it (as the firmware's [attitude] kind = \"dataset\";\n"
    "                         docs/SKY_DESCRIPTOR.md, \"Tilt\"); default none\n"
    "  --max-tilt DEG         with --attitude dataset: the largest tilt the cap must\n"
    "                         survive, 0..80 (default: [attitude] max_tilt_deg of --config)\n"
    "\n"
    "Without --gt and --tolerance-m, both datasets need poses: the truth of a query is the\n"
    "reference recorded nearest to it, correct within --frame-tolerance frames.\n"
    "  --force                write into an --out folder that is not empty (its\n"
    "                         matches.csv, metrics.json and SVGs are replaced)\n"
    "\n"
    "Writes OUT/matches.csv, OUT/metrics.json, OUT/pr.svg, OUT/correspondence.svg, each\n"
    "to a temporary file renamed into place once complete: a full disk leaves the\n"
    "previous file (or none), never a truncated one.\n"
    "Every run also replays the firmware's state machine ([state] of --config) over\n"
    "its matches: matches.csv gives each frame's state, metrics.json the share of\n"
    "LOCALISED frames that are correct. Sky runs with horizon strips also print it\n"
    "with frames whose 1D SURF score against the matched frame is below 25..400\n"
    "counted as no match (landmark confirmation, docs/RESULTS.md).\n";

enum class Method : std::uint8_t { kSky, kVanilla, kFabmap, kSurf1d };

const char* MethodName(Method m) {
  switch (m) {
    case Method::kSky:
      return "sky";
    case Method::kVanilla:
      return "vanilla";
    case Method::kFabmap:
      return "fabmap";
    case Method::kSurf1d:
      return "surf1d";
  }
  return "?";
}

const char* MatcherName(Matcher m) {
  return m == Matcher::kRouteFilter ? "filter" : "openseqslam";
}

struct EvalOptions {
  std::string reference;
  std::string query;
  std::string out;
  bool force = false;  // --force: --out may hold files already
  std::string gt_file;
  double tolerance_m = -1.0;  // < 0: not given
  int frame_tolerance = 5;
  std::vector<Method> methods;
  std::vector<Matcher> matchers;
  std::vector<int> ds_list;
  std::optional<int> max_advance;
  std::optional<double> keyframe_noise_factor;
  std::string config_file;
  Config config = DefaultConfig();  // --config FILE, then the flags above
  bool streaming = false;
  std::string vocab;   // --vocab FILE (fabmap)
  std::string camera;  // --camera FILE
  std::optional<dsp::LensModel> lens;
  std::optional<double> fov_deg;
  std::optional<int> bands;  // --bands: replaces [descriptor] bands of the configuration
  int jobs = DefaultJobs();
  bool vanilla_bytes = true;           // --vanilla-precision byte (the default) or float
  bool attitude_from_dataset = false;  // --attitude dataset
  std::optional<double> max_tilt_deg;  // --max-tilt
};

bool ParseIntArg(const char* s, int* out) {
  const char* end = s + std::strlen(s);
  auto [p, ec] = std::from_chars(s, end, *out);
  return ec == std::errc() && p == end && end != s;
}

bool ParseDoubleArg(const char* s, double* out) {
  const char* end = s + std::strlen(s);
  auto [p, ec] = std::from_chars(s, end, *out);
  return ec == std::errc() && p == end && end != s && std::isfinite(*out);
}

// Returns kExitOk, or kExitUsage after printing the problem.
int ParseArgs(std::span<char* const> args, EvalOptions* o, bool* help) {
  auto fail = [](std::string_view what, const char* a) { return UsageError("eval", what, a); };
  bool batch = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const std::string_view a = args[i];
    auto value = [&]() -> const char* { return i + 1 < args.size() ? args[++i] : nullptr; };
    if (a == "--help" || a == "-h") {
      *help = true;
      return kExitOk;
    }
    if (a == "--batch") {
      batch = true;
      continue;
    }
    if (a == "--streaming") {
      o->streaming = true;
      continue;
    }
    if (a == "--force") {
      o->force = true;
      continue;
    }
    const char* v = value();
    if (v == nullptr)
      return fail("%s needs a value", args[i]);
    if (a == "--reference") {
      o->reference = v;
    } else if (a == "--query") {
      o->query = v;
    } else if (a == "--out") {
      o->out = v;
    } else if (a == "--gt") {
      o->gt_file = v;
    } else if (a == "--tolerance-m") {
      if (!ParseDoubleArg(v, &o->tolerance_m) || o->tolerance_m <= 0)
        return fail("--tolerance-m '%s': give a distance in metres > 0", v);
    } else if (a == "--frame-tolerance") {
      if (!ParseIntArg(v, &o->frame_tolerance) || o->frame_tolerance < 0)
        return fail("--frame-tolerance '%s': give a whole number of frames >= 0", v);
    } else if (a == "--method") {
      if (std::strcmp(v, "sky") == 0) {
        o->methods.push_back(Method::kSky);
      } else if (std::strcmp(v, "vanilla") == 0) {
        o->methods.push_back(Method::kVanilla);
      } else if (std::strcmp(v, "fabmap") == 0) {
        o->methods.push_back(Method::kFabmap);
      } else if (std::strcmp(v, "surf1d") == 0) {
        o->methods.push_back(Method::kSurf1d);
      } else {
        return fail("--method '%s': use sky, vanilla, fabmap or surf1d", v);
      }
    } else if (a == "--vocab") {
      o->vocab = v;
    } else if (a == "--matcher") {
      if (std::strcmp(v, "filter") == 0) {
        o->matchers.push_back(Matcher::kRouteFilter);
      } else if (std::strcmp(v, "openseqslam") == 0) {
        o->matchers.push_back(Matcher::kOpenSeqSlam);
      } else {
        return fail("--matcher '%s': use filter or openseqslam", v);
      }
    } else if (a == "--max-advance") {
      int k = 0;
      if (!ParseIntArg(v, &k) || k < 1 || k > dsp::kMaxAdvance)
        return fail("--max-advance '%s': give 1..64 route rows per frame", v);
      o->max_advance = k;
    } else if (a == "--keyframe-noise") {
      double f = 0;
      if (!ParseDoubleArg(v, &f) || f < 0 || f > 100)
        return fail("--keyframe-noise '%s': give 0..100 (0 keeps every reference frame)", v);
      o->keyframe_noise_factor = f;
    } else if (a == "--config") {
      o->config_file = v;
    } else if (a == "--ds") {
      int ds = 0;
      if (!ParseIntArg(v, &ds) || ds < 1 || ds > dsp::kMaxSequenceLength)
        return fail("--ds '%s': give a sequence length of 1..1000 frames", v);
      o->ds_list.push_back(ds);
    } else if (a == "--camera") {
      o->camera = v;
    } else if (a == "--lens") {
      dsp::LensModel model;
      if (!dsp::ParseLensModel(v, &model) || model == dsp::LensModel::kKannalaBrandt ||
          model == dsp::LensModel::kOCamCalib || model == dsp::LensModel::kPinhole)
        return fail(
            "--lens '%s': use equidistant, equisolid or equirectangular (other models "
            "need a camera file)",
            v);
      o->lens = model;
    } else if (a == "--fov") {
      double fov = 0;
      if (!ParseDoubleArg(v, &fov) || fov <= 0 || fov > 360)
        return fail("--fov '%s': give a field of view in (0, 360] degrees", v);
      o->fov_deg = fov;
    } else if (a == "--attitude") {
      if (std::strcmp(v, "dataset") == 0)
        o->attitude_from_dataset = true;
      else if (std::strcmp(v, "none") == 0)
        o->attitude_from_dataset = false;
      else
        return fail("--attitude '%s': give none or dataset", v);
    } else if (a == "--max-tilt") {
      double t = 0;
      if (!ParseDoubleArg(v, &t) || t < 0 || t > 80)
        return fail("--max-tilt '%s': give a tilt of 0..80 degrees", v);
      o->max_tilt_deg = t;
    } else if (a == "--jobs") {
      if (!ParseIntArg(v, &o->jobs) || o->jobs < 1 || o->jobs > 1024)
        return fail("--jobs '%s': give a number of threads, 1..1024", v);
    } else if (a == "--vanilla-precision") {
      if (std::strcmp(v, "float") == 0) {
        o->vanilla_bytes = false;
      } else if (std::strcmp(v, "byte") == 0) {
        o->vanilla_bytes = true;
      } else {
        return fail("--vanilla-precision '%s': use float or byte", v);
      }
    } else if (a == "--bands") {
      int bands = 0;
      if (!ParseIntArg(v, &bands) || bands < 1 || bands > 512)
        return fail("--bands '%s': give 1..512", v);
      o->bands = bands;
    } else {
      return fail("unknown option '%s'", args[i]);
    }
  }
  if (o->reference.empty() || o->query.empty() || o->out.empty())
    return fail("%s", "--reference, --query and --out are required");
  if (batch && o->streaming)
    return fail("%s", "--batch and --streaming exclude each other");
  if (!o->gt_file.empty() && o->tolerance_m > 0)
    return fail("%s", "--gt and --tolerance-m exclude each other");
  const bool fabmap_asked =
      std::find(o->methods.begin(), o->methods.end(), Method::kFabmap) != o->methods.end();
  if (fabmap_asked && o->vocab.empty())
    return fail("%s", "--method fabmap needs --vocab FILE (write one with skyloc fabmap-train)");
  if (o->max_tilt_deg && !o->attitude_from_dataset)
    return fail("%s", "--max-tilt sets the gravity-aligned cap: add --attitude dataset");
  if (o->methods.empty()) {
    o->methods = {Method::kSky, Method::kVanilla};
    if (!o->vocab.empty())
      o->methods.push_back(Method::kFabmap);
  }
  if (o->matchers.empty()) {
    o->matchers = {(batch || o->streaming) ? Matcher::kOpenSeqSlam : Matcher::kRouteFilter};
  } else if ((batch || o->streaming) && std::find(o->matchers.begin(), o->matchers.end(),
                                                  Matcher::kOpenSeqSlam) == o->matchers.end()) {
    return fail("%s",
                "--batch and --streaming choose openseqslam's window: add --matcher openseqslam");
  }
  std::sort(o->matchers.begin(), o->matchers.end());
  o->matchers.erase(std::unique(o->matchers.begin(), o->matchers.end()), o->matchers.end());
  if (o->ds_list.empty())
    o->ds_list = {1, 10, 20};
  std::sort(o->methods.begin(), o->methods.end());
  o->methods.erase(std::unique(o->methods.begin(), o->methods.end()), o->methods.end());
  return kExitOk;
}

// ---- Descriptors -----------------------------------------------------------------------

struct Descriptors {
  int dim = 0;
  int count = 0;
  std::vector<float> values;        // count x dim
  std::vector<std::uint8_t> bytes;  // count x dim, dsp::QuantiseToBytes (vanilla, batch)
  // Sky: every frame's horizon strip as the route stores it ([heading]; 0 columns: none,
  // or the lens does not see the band).
  int strip_columns = 0;
  std::vector<std::uint8_t> strips;  // count x strip_columns
  std::span<const float> all() const { return values; }
};

// Which forms of the descriptors the runs read: floats (every matcher), bytes (vanilla in
// the batch matcher, --vanilla-precision byte), or both.
struct DescriptorForms {
  bool floats = true;
  bool bytes = false;
};

Result<Descriptors> ComputeDescriptors(Method method, const std::string& dir, const EvalOptions& o,
                                       DescriptorForms forms) {
  drivers::DatasetCamera camera(dir);
  SKYLOC_TRY(camera.Open());
  SKYLOC_TRY(camera.Start());
  Descriptors d;
  dsp::Lens lens_of_run;
  dsp::SkyDescriptorOptions options_of_run;
  if (method == Method::kSky) {
    // The lens: --camera, else the dataset's camera.toml, else describe's default for a
    // square-ish image (equidistant, 185 degrees); --lens/--fov override any of them.
    dsp::LensParams lp;
    std::string source = "default lens (equidistant 185 degrees)";
    const std::string& file = !o.camera.empty() ? o.camera : camera.dataset().camera_toml;
    if (!file.empty()) {
      SKYLOC_TRY_ASSIGN(lp, drivers::LoadCameraFile(file.c_str()));
      source = file;
      if (lp.width != camera.info().width || lp.height != camera.info().height) {
        return Status::Error(StatusCode::kInvalidArgument,
                             "dataset %s has %dx%d frames but camera file %s describes %dx%d: "
                             "pass the camera file made for this camera with --camera",
                             dir.c_str(), camera.info().width, camera.info().height, file.c_str(),
                             lp.width, lp.height);
      }
    } else if (Result<dsp::LensParams> guess =
                   drivers::GuessLensForImage(camera.info().width, camera.info().height,
                                              camera.dataset().FramePath(0).c_str());
               guess.ok()) {
      lp = *guess;  // as `skyloc describe` guesses from the image's shape
      if (lp.model == dsp::LensModel::kEquirectangular)
        source = "default lens (equirectangular: a 2:1 image)";
    } else if (!o.lens) {
      return Status::Error(StatusCode::kInvalidArgument, "%s or --lens", guess.status().message());
    } else {
      lp.width = camera.info().width;  // --lens says what the shape could not
      lp.height = camera.info().height;
    }
    if (o.lens)
      lp.model = *o.lens;
    if (o.fov_deg)
      lp.fov_deg = *o.fov_deg;
    SKYLOC_TRY(drivers::InitLens(lp, source.c_str(), &lens_of_run));
    // The firmware's descriptor ([descriptor] and [segmentation] of --config, else the
    // built-in defaults), as the robot computes it; --bands has already replaced the bands
    // (Evaluate).
    options_of_run =
        EvalSkyDescriptorOptions(o.config, lens_of_run, o.attitude_from_dataset, o.max_tilt_deg);
    d.dim = options_of_run.bands;
  } else {
    d.dim = dsp::kVanillaDescriptorSize;
  }
  // The firmware's horizon strip, for the heading of the correctly matched frames.
  dsp::HorizonStrip horizon;
  const std::optional<dsp::HorizonStripOptions> strip_options = StripOptionsFrom(o.config);
  if (method == Method::kSky && strip_options) {
    if (const dsp::HorizonStripError e = horizon.Init(lens_of_run, *strip_options);
        e == dsp::HorizonStripError::kOk)
      d.strip_columns = strip_options->n_azimuth;
    else
      std::fprintf(stderr, "skyloc eval: %s: no heading: %s\n", dir.c_str(),
                   dsp::HorizonStripErrorMessage(e));
  }
  const auto strip_columns = static_cast<std::size_t>(d.strip_columns);
  // The frames are decoded and described on --jobs threads, each with its own sky
  // descriptor (it holds scratch); a frame's descriptor does not depend on the thread.
  const drivers::Dataset& dataset = camera.dataset();
  const drivers::CameraInfo info = camera.info();
  const std::size_t n = dataset.frames.size();
  const auto dim = static_cast<std::size_t>(d.dim);
  // Only the forms some run reads are kept: a bytes-only run holds a quarter of the
  // floats' memory (2 kB a vanilla frame instead of 8 kB).
  if (forms.floats)
    d.values.resize(n * dim);
  if (forms.bytes)
    d.bytes.resize(n * dim);
  d.strips.resize(n * strip_columns);
  const int workers = std::clamp(o.jobs, 1, std::max(1, static_cast<int>(n)));
  std::vector<std::vector<float>> rows(static_cast<std::size_t>(workers), std::vector<float>(dim));
  std::vector<std::vector<float>> strip_rows(static_cast<std::size_t>(workers),
                                             std::vector<float>(strip_columns));
  std::vector<std::unique_ptr<dsp::SkyDescriptor>> skies;
  if (method == Method::kSky) {
    for (int w = 0; w < workers; ++w) {
      skies.push_back(std::make_unique<dsp::SkyDescriptor>());
      const dsp::DescriptorError de = skies.back()->Init(lens_of_run, options_of_run);
      if (!de.ok()) {
        return Status::Error(StatusCode::kInvalidArgument, "sky descriptor for %s: %s", dir.c_str(),
                             de.message);
      }
    }
  }
  std::mutex failure_mutex;
  std::size_t failed_at = n;  // the first frame (in order) that failed, and why
  Status failure;
  std::atomic<long> described{0};
  Progress progress(std::string(MethodName(method)) + " descriptors of " + dir, "frames",
                    static_cast<long>(n));
  const auto describe = [&](std::size_t i, int worker) -> Status {
    SKYLOC_TRY_ASSIGN(const drivers::OwnedImage image,
                      drivers::LoadImage(dataset.FramePath(i).c_str()));
    if (image.width() != info.width || image.height() != info.height ||
        image.format() != info.format) {
      return Status::Error(StatusCode::kDataLoss,
                           "dataset %s: frame %zu (%s) is %dx%d %s but the first frame is %dx%d %s",
                           dataset.dir.c_str(), i, dataset.frames[i].file.c_str(), image.width(),
                           image.height(), dsp::PixelFormatName(image.format()), info.width,
                           info.height, dsp::PixelFormatName(info.format));
    }
    const std::span<float> out = forms.floats
                                     ? std::span<float>(d.values.data() + i * dim, dim)
                                     : std::span<float>(rows[static_cast<std::size_t>(worker)]);
    if (method == Method::kSky) {
      const std::optional<dsp::Attitude>& attitude = dataset.frames[i].attitude;
      if (o.attitude_from_dataset && !attitude) {
        return Status::Error(StatusCode::kInvalidArgument,
                             "%s has no roll and pitch recorded (frames.csv): --attitude dataset "
                             "needs the attitude or pose columns (docs/DATASETS.md), or drop it",
                             dataset.FramePath(i).c_str());
      }
      const dsp::DescriptorError de = skies[static_cast<std::size_t>(worker)]->Compute(
          image.view(), out, nullptr, o.attitude_from_dataset ? &*attitude : nullptr);
      if (!de.ok()) {
        return Status::Error(StatusCode::kDataLoss, "%s: sky descriptor: %s",
                             dataset.FramePath(i).c_str(), de.message);
      }
      if (strip_columns > 0) {
        std::vector<float>& strip = strip_rows[static_cast<std::size_t>(worker)];
        if (const dsp::HorizonStripError e = horizon.Extract(image.view(), strip);
            e != dsp::HorizonStripError::kOk)
          return Status::Error(StatusCode::kDataLoss, "%s: horizon strip: %s",
                               dataset.FramePath(i).c_str(), dsp::HorizonStripErrorMessage(e));
        if (const dsp::HorizonStripError e = dsp::StripToBytes(
                strip, std::span<std::uint8_t>(d.strips).subspan(i * strip_columns, strip_columns));
            e != dsp::HorizonStripError::kOk)
          return Status::Error(StatusCode::kInternal, "%s: horizon strip: %s",
                               dataset.FramePath(i).c_str(), dsp::HorizonStripErrorMessage(e));
      }
    } else {
      const dsp::VanillaError ve = dsp::VanillaDescriptor(image.view(), out);
      if (ve != dsp::VanillaError::kOk) {
        return Status::Error(StatusCode::kDataLoss, "%s: %s", dataset.FramePath(i).c_str(),
                             dsp::VanillaErrorMessage(ve));
      }
    }
    if (forms.bytes)
      dsp::QuantiseToBytes(out, std::span<std::uint8_t>(d.bytes.data() + i * dim, dim));
    return Status::Ok();
  };
  ParallelFor(workers, static_cast<int>(n), [&](int task, int worker) {
    const auto i = static_cast<std::size_t>(task);
    {
      const std::lock_guard<std::mutex> lock(failure_mutex);
      if (failed_at < i)
        return;  // an earlier frame failed: that is the error to report
    }
    const Status s = describe(i, worker);
    if (!s.ok()) {
      const std::lock_guard<std::mutex> lock(failure_mutex);
      if (i < failed_at) {
        failed_at = i;
        failure = s;
      }
    }
    const long done = described.fetch_add(1) + 1;
    if (worker == 0)
      progress.Update(done);
  });
  SKYLOC_TRY(failure);
  progress.Finish();
  d.count = static_cast<int>(n);
  camera.Close();
  return d;
}

// ---- Ground truth ----------------------------------------------------------------------

struct GroundTruth {
  std::vector<dsp::TruthInterval> reference;       // per query frame (dsp/place_metrics.h)
  dsp::MatchTolerance tolerance;                   // frames, or metres with --tolerance-m
  std::vector<dsp::Position3> ref_xyz, query_xyz;  // empty with --gt FILE
  std::string description;
};

dsp::Position3 PositionOf(const drivers::DatasetFrame& frame) {
  return {frame.pose->x_m, frame.pose->y_m, frame.pose->z_m};
}

Status ReadGroundTruthCsv(const std::string& path, int n_query, int n_ref, GroundTruth* gt) {
  std::FILE* f = std::fopen(path.c_str(), "rb");
  if (f == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot open ground truth %s", path.c_str());
  }
  gt->reference.assign(static_cast<std::size_t>(n_query), dsp::TruthInterval{});
  std::vector<bool> seen(static_cast<std::size_t>(n_query), false);
  char line[256];
  int line_no = 0;
  Status status;
  while (status.ok() && std::fgets(line, sizeof line, f) != nullptr) {
    ++line_no;
    std::string_view s(line);
    while (!s.empty() && (s.back() == '\n' || s.back() == '\r'))
      s.remove_suffix(1);
    if (line_no == 1) {
      if (s != "query_index,reference_index") {
        status = Status::Error(StatusCode::kInvalidArgument,
                               "%s:1: header must be 'query_index,reference_index'", path.c_str());
      }
      continue;
    }
    if (s.empty())
      continue;
    const std::size_t comma = s.find(',');
    int q = 0, r = 0;
    auto parse = [](std::string_view t, int* v) {
      auto [p, ec] = std::from_chars(t.data(), t.data() + t.size(), *v);
      return ec == std::errc() && p == t.data() + t.size() && !t.empty();
    };
    if (comma == std::string_view::npos || !parse(s.substr(0, comma), &q) ||
        !parse(s.substr(comma + 1), &r)) {
      status = Status::Error(StatusCode::kInvalidArgument,
                             "%s:%d: expected two integers 'query_index,reference_index'",
                             path.c_str(), line_no);
    } else if (q < 0 || q >= n_query) {
      status = Status::Error(StatusCode::kInvalidArgument,
                             "%s:%d: query_index %d outside the query run's 0..%d", path.c_str(),
                             line_no, q, n_query - 1);
    } else if (r < -1 || r >= n_ref) {
      status =
          Status::Error(StatusCode::kInvalidArgument, "%s:%d: reference_index %d outside -1..%d",
                        path.c_str(), line_no, r, n_ref - 1);
    } else if (seen[static_cast<std::size_t>(q)]) {
      status = Status::Error(StatusCode::kInvalidArgument, "%s:%d: query_index %d given twice",
                             path.c_str(), line_no, q);
    } else {
      seen[static_cast<std::size_t>(q)] = true;
      gt->reference[static_cast<std::size_t>(q)] = dsp::TruthAtFrame(r);
    }
  }
  const bool read_error = std::ferror(f) != 0;
  std::fclose(f);
  SKYLOC_TRY(status);
  if (read_error)
    return Status::Error(StatusCode::kDataLoss, "cannot read %s", path.c_str());
  if (line_no == 0)
    return Status::Error(StatusCode::kInvalidArgument, "%s: empty file", path.c_str());
  return Status::Ok();
}

Result<GroundTruth> MakeGroundTruth(const EvalOptions& o, const drivers::Dataset& ref,
                                    const drivers::Dataset& query) {
  GroundTruth gt;
  const int n_query = static_cast<int>(query.frames.size());
  const int n_ref = static_cast<int>(ref.frames.size());
  gt.tolerance.frames = o.frame_tolerance;
  if (!o.gt_file.empty()) {
    SKYLOC_TRY(ReadGroundTruthCsv(o.gt_file, n_query, n_ref, &gt));
    gt.description = "file " + o.gt_file;
    return gt;
  }
  if (!ref.has_poses || !query.has_poses) {
    return Status::Error(StatusCode::kInvalidArgument,
                         "no ground truth: %s has no poses in frames.csv; pass --gt FILE "
                         "(query_index,reference_index)",
                         ref.has_poses ? query.dir.c_str() : ref.dir.c_str());
  }
  const bool by_distance = o.tolerance_m > 0;
  gt.tolerance.metres = by_distance ? o.tolerance_m : 0;
  gt.reference.assign(static_cast<std::size_t>(n_query), dsp::TruthInterval{});
  for (const drivers::DatasetFrame& f : ref.frames)
    gt.ref_xyz.push_back(PositionOf(f));
  for (const drivers::DatasetFrame& f : query.frames)
    gt.query_xyz.push_back(PositionOf(f));
  // With a distance tolerance, a query farther than it from the whole route is off it.
  dsp::GroundTruthFromPositions(
      gt.ref_xyz, gt.query_xyz,
      by_distance ? o.tolerance_m : std::numeric_limits<double>::infinity(), gt.reference);
  char text[96];
  if (by_distance) {
    std::snprintf(text, sizeof text, "poses, correct within %.3g m", o.tolerance_m);
  } else {
    std::snprintf(text, sizeof text, "poses (nearest reference frames), correct within %d frames",
                  o.frame_tolerance);
  }
  gt.description = text;
  return gt;
}

// ---- Runs --------------------------------------------------------------------------------

struct Run {
  Method method = Method::kVanilla;
  Matcher matcher = Matcher::kRouteFilter;
  std::string matcher_name;  // MatcherName(matcher), or "fabmap2" for FAB-MAP's own inference
  int ds = 0;
  std::vector<dsp::SeqSlamMatch> matches;      // per query frame
  std::vector<dsp::LocalisationState> states;  // per query frame: the state machine replayed
  int localised = 0, localised_correct = 0;
  std::vector<int> evaluated_queries;  // queries with a match, in order
  std::vector<dsp::EvaluatedMatch> evaluated;
  std::vector<dsp::PrPoint> curve;
  dsp::PrSummary summary;
  std::string label;
  // Sky with strips and poses: the heading error of the correctly matched frames
  // (HeadingErrors), by the cross-correlation and by 1D SURF + RANSAC.
  bool heading_evaluated = false;
  dsp::HeadingErrorSummary heading_correlation, heading_surf;
  // Landmark confirmation (issue 13 item 2, LandmarkConfirmation): LOCALISED frames and
  // how many are correct when a frame counts as a match only if the 1D SURF recognition
  // score of its strip against the matched frame's reaches each threshold.
  struct Confirmation {
    double min_score = 0;
    int localised = 0, localised_correct = 0;
  };
  std::vector<Confirmation> confirmation;
};

Status RunMatcher(const Descriptors& ref, const Descriptors& query, const EvalOptions& o,
                  Run* run) {
  run->matches.assign(static_cast<std::size_t>(query.count), dsp::SeqSlamMatch{});
  const auto row = [](const Descriptors& d, int i) {
    return d.all().subspan(static_cast<std::size_t>(i * d.dim), static_cast<std::size_t>(d.dim));
  };
  dsp::SeqSlamError e = dsp::SeqSlamError::kOk;
  char what[96];
  std::snprintf(what, sizeof what, "%s %s ds %d", MethodName(run->method),
                MatcherName(run->matcher), run->ds);
  Progress progress(what, "query frames matched", query.count);
  if (run->matcher == Matcher::kRouteFilter) {
    // The firmware's engine, as repeat runs it: causal, one query at a time.
    dsp::RouteFilterParams p = o.config.seqslam.filter;
    p.sequence_length = run->ds;
    dsp::RouteFilter engine;
    e = engine.Init(p, ref.dim, std::max(1, ref.count));
    for (int r = 0; e == dsp::SeqSlamError::kOk && r < ref.count; ++r)
      e = engine.AddReference(row(ref, r));
    if (e == dsp::SeqSlamError::kOk)
      e = engine.FinishRoute();
    for (int t = 0; e == dsp::SeqSlamError::kOk && t < query.count; ++t) {
      e = engine.Step(row(query, t), &run->matches[static_cast<std::size_t>(t)]);
      progress.Update(t + 1);
    }
  } else if (o.streaming) {
    dsp::SeqSlamParams p;
    p.sequence_length = run->ds;
    dsp::StreamingSeqSlam engine;
    e = engine.Init(p, ref.dim, std::max(1, ref.count));
    for (int r = 0; e == dsp::SeqSlamError::kOk && r < ref.count; ++r)
      e = engine.AddReference(row(ref, r));
    for (int t = 0; e == dsp::SeqSlamError::kOk && t < query.count; ++t) {
      e = engine.Step(row(query, t), &run->matches[static_cast<std::size_t>(t)]);
      progress.Update(t + 1);
    }
  } else {
    // OpenSeqSLAM's batch engine, blocked: n_ref x (block + ds - 1) floats instead of the
    // whole matrix, on --jobs threads, the same matches bit for bit (docs/SEQSLAM.md).
    dsp::SeqSlamParams p;
    p.sequence_length = run->ds;
    const bool bytes = !ref.bytes.empty();
    const auto rows = [&](const Descriptors& d) {
      return bytes ? dsp::DescriptorRows::Bytes(d.bytes, d.dim)
                   : dsp::DescriptorRows::Floats(d.values, d.dim);
    };
    dsp::BlockedSeqSlamOptions bo;
    // Enough column groups per block to keep every thread busy; the result does not
    // depend on the block size.
    bo.block_columns = std::max(256, 4 * o.jobs * dsp::BlockedSeqSlam::kColumnGroup);
    dsp::BlockedSeqSlam engine;
    e = engine.Init(rows(ref), rows(query), p, dsp::SeqSlamWindow::kCentred, bo, run->matches);
    if (e == dsp::SeqSlamError::kOk)
      RunBlockedSeqSlam(engine, o.jobs, [&](int done) { progress.Update(done); });
  }
  progress.Finish();
  if (e != dsp::SeqSlamError::kOk) {
    return Status::Error(StatusCode::kInvalidArgument, "%s (%s, ds %d): %s",
                         MatcherName(run->matcher), MethodName(run->method), run->ds,
                         dsp::SeqSlamErrorMessage(e));
  }
  return Status::Ok();
}

// FAB-MAP 2.0: each query's most probable reference place, with uniqueness = 1 - its
// posterior (lower = more distinct, as SeqSLAM's ratio, so the same PR sweep applies:
// accepting uniqueness <= u is accepting p(place | query) >= 1 - u).
Status RunFabmap(const EvalOptions& o, Run* run) {
  run->method = Method::kFabmap;
  run->matcher_name = "fabmap2";
  run->ds = 1;
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
  run->matches.assign(found.size(), dsp::SeqSlamMatch{});
  for (std::size_t i = 0; i < found.size(); ++i) {
    const tools::FabmapQueryMatch& f = found[i];
    dsp::SeqSlamMatch& m = run->matches[i];
    if (f.reference < 0)
      continue;
    m.valid = true;
    m.reference = m.row = m.start = f.reference;
    m.score = static_cast<float>(-std::log(std::max(f.p_reference, 1e-300)));
    m.uniqueness = static_cast<float>(f.uniqueness);
    m.confidence = 1.0f - m.uniqueness;
  }
  return Status::Ok();
}

bool IsCorrect(const GroundTruth& gt, int q, int matched) {
  const auto i = static_cast<std::size_t>(q);
  return dsp::MatchIsCorrect(matched, gt.reference[i], gt.tolerance, gt.ref_xyz,
                             i < gt.query_xyz.size() ? gt.query_xyz[i] : dsp::Position3{});
}

void Score(const GroundTruth& gt, Run* run) {
  for (std::size_t q = 0; q < run->matches.size(); ++q) {
    const dsp::SeqSlamMatch& m = run->matches[q];
    if (!m.valid)
      continue;
    dsp::EvaluatedMatch e;
    e.uniqueness = m.uniqueness;
    e.has_ground_truth = gt.reference[q].has_truth();
    e.correct = IsCorrect(gt, static_cast<int>(q), m.reference);
    run->evaluated_queries.push_back(static_cast<int>(q));
    run->evaluated.push_back(e);
  }
  std::vector<std::size_t> order(run->evaluated.size());
  run->curve.resize(run->evaluated.size());
  run->curve.resize(dsp::PrecisionRecallCurve(run->evaluated, order, run->curve));
  run->summary = dsp::SummarisePrecisionRecall(run->evaluated, run->curve);
  for (std::size_t k = 0; k < run->evaluated_queries.size(); ++k) {
    if (run->states[static_cast<std::size_t>(run->evaluated_queries[k])] ==
        dsp::LocalisationState::kLocalised) {
      ++run->localised;
      run->localised_correct += run->evaluated[k].correct ? 1 : 0;
    }
  }
  run->label = std::string(MethodName(run->method)) + " " + run->matcher_name +
               " ds=" + std::to_string(run->ds);
}

// ---- 1D SURF as a place recogniser (issue 13 item 3) --------------------------------------

// Every frame's 1D SURF features from its horizon strip as the route stores it ([heading]
// band through the sky method's lens, rounded to bytes), the strongest surf_max_features.
Result<std::vector<std::vector<dsp::Surf1dFeature>>> StripFeatures(const Descriptors& d,
                                                                   const HeadingConfig& config) {
  const dsp::HeadingOptions& options = config.estimate;
  dsp::Surf1d surf;
  if (const dsp::Surf1dError e = surf.Init(d.strip_columns, options.features);
      e != dsp::Surf1dError::kOk)
    return Status::Error(StatusCode::kInvalidArgument, "surf1d: %s", dsp::Surf1dErrorMessage(e));
  const auto n = static_cast<std::size_t>(d.strip_columns);
  std::vector<float> strip(n);
  std::vector<dsp::Surf1dFeature> found(static_cast<std::size_t>(options.max_features));
  std::vector<std::vector<dsp::Surf1dFeature>> features(static_cast<std::size_t>(d.count));
  for (std::size_t i = 0; i < features.size(); ++i) {
    for (std::size_t c = 0; c < n; ++c)
      strip[c] = d.strips[i * n + c];
    int count = 0;
    if (const dsp::Surf1dError e = surf.Detect(strip, found, &count); e != dsp::Surf1dError::kOk)
      return Status::Error(StatusCode::kInvalidArgument, "surf1d: %s", dsp::Surf1dErrorMessage(e));
    features[i].assign(found.begin(), found.begin() + count);
  }
  return features;
}

// The best-scoring reference of one query's scores (higher = more alike). Uniqueness as
// SeqSLAM's, lower = more distinctive: the best score outside +-rwindow/2 frames of the
// best divided by the best. No match when every score is 0 (no RANSAC line anywhere).
dsp::SeqSlamMatch BestScore(std::span<const float> scores, int rwindow) {
  dsp::SeqSlamMatch m;
  const auto best = std::max_element(scores.begin(), scores.end());
  if (best == scores.end() || !(*best > 0.0f))
    return m;
  const int r = static_cast<int>(best - scores.begin());
  float runner_up = 0.0f;
  for (int i = 0; i < static_cast<int>(scores.size()); ++i)
    if (std::abs(i - r) > rwindow / 2)
      runner_up = std::max(runner_up, scores[static_cast<std::size_t>(i)]);
  m.valid = true;
  m.reference = m.row = m.start = r;
  m.score = *best;
  m.uniqueness = runner_up / *best;
  m.confidence = 1.0f - m.uniqueness;
  return m;
}

// `--method surf1d`: the recognition score (NN with RANSAC: sum of 1 / distance over the
// RANSAC inliers, the paper's) of every query frame against every reference frame, then
// one run "single" (each query's best frame) and one OpenSeqSLAM run per --ds over the
// differences best - score (SeqSLAM's local contrast enhancement normalises each column,
// so only the order and spread of a query's scores matter).
// `rd` and `qd` are the sky method's descriptors of the two runs: surf1d reads their
// horizon strips.
Status RunSurf1dMethod(const EvalOptions& o, const GroundTruth& gt, const Descriptors& rd,
                       const Descriptors& qd, std::vector<Run>* runs) {
  if (!o.config.heading.enabled())
    return Status::Error(StatusCode::kInvalidArgument,
                         "--method surf1d needs horizon strips: [heading] strip_columns is 0 "
                         "in --config; set it (default 360)");
  if (rd.strip_columns == 0 || rd.strip_columns != qd.strip_columns)
    return Status::Error(StatusCode::kInvalidArgument,
                         "--method surf1d: the lens does not see the [heading] band in both "
                         "datasets (see the message above); set the band or the camera file");
  SKYLOC_TRY_ASSIGN(const auto ref_features, StripFeatures(rd, o.config.heading));
  SKYLOC_TRY_ASSIGN(const auto query_features, StripFeatures(qd, o.config.heading));
  const dsp::HeadingOptions& options = o.config.heading.estimate;
  const auto n_ref = static_cast<std::size_t>(rd.count);
  const auto n_query = static_cast<std::size_t>(qd.count);
  std::vector<float> scores(n_query * n_ref);  // query-major, as SeqSlamFromDifferences
  const int workers = std::clamp(o.jobs, 1, std::max(1, qd.count));
  std::vector<dsp::LandmarkMatcher> matchers(static_cast<std::size_t>(workers));
  for (dsp::LandmarkMatcher& m : matchers) {
    if (const dsp::Surf1dError e = m.Init(options.max_features, options.matching);
        e != dsp::Surf1dError::kOk)
      return Status::Error(StatusCode::kInvalidArgument, "surf1d: %s", dsp::Surf1dErrorMessage(e));
  }
  Progress progress("surf1d scores", "query frames", qd.count);
  std::atomic<long> done{0};
  ParallelFor(workers, qd.count, [&](int q, int worker) {
    const auto qi = static_cast<std::size_t>(q);
    for (std::size_t r = 0; r < n_ref; ++r) {
      dsp::LandmarkMatch m;
      // Sized for max_features, which bounds every feature list: cannot fail.
      (void)matchers[static_cast<std::size_t>(worker)].Match(ref_features[r], query_features[qi],
                                                             rd.strip_columns, &m);
      scores[qi * n_ref + r] = m.model_found ? static_cast<float>(m.ransac_score) : 0.0f;
    }
    const long finished = ++done;
    if (worker == 0)
      progress.Update(finished);
  });
  progress.Finish();

  Run single;
  single.method = Method::kSurf1d;
  single.matcher = Matcher::kOpenSeqSlam;
  single.matcher_name = "single";
  single.ds = 1;
  single.matches.resize(n_query);
  for (std::size_t q = 0; q < n_query; ++q)
    single.matches[q] =
        BestScore(std::span(scores).subspan(q * n_ref, n_ref), o.config.seqslam.rwindow());
  runs->push_back(std::move(single));

  std::vector<float> differences(scores.size());
  for (std::size_t q = 0; q < n_query; ++q) {
    const std::span<const float> column = std::span(scores).subspan(q * n_ref, n_ref);
    const float best = *std::max_element(column.begin(), column.end());
    for (std::size_t r = 0; r < n_ref; ++r)
      differences[q * n_ref + r] = best - column[r];
  }
  for (const int ds : o.ds_list) {
    Run run;
    run.method = Method::kSurf1d;
    run.matcher = Matcher::kOpenSeqSlam;
    run.matcher_name = MatcherName(Matcher::kOpenSeqSlam);
    run.ds = ds;
    run.matches.resize(n_query);
    dsp::SeqSlamParams p;
    p.sequence_length = ds;
    if (const dsp::SeqSlamError e = dsp::SeqSlamFromDifferences(
            differences, rd.count, qd.count, p, dsp::SeqSlamWindow::kCentred, run.matches);
        e != dsp::SeqSlamError::kOk)
      return Status::Error(StatusCode::kInvalidArgument, "surf1d openseqslam ds %d: %s", ds,
                           dsp::SeqSlamErrorMessage(e));
    runs->push_back(std::move(run));
  }
  for (std::size_t i = runs->size() - 1 - o.ds_list.size(); i < runs->size(); ++i) {
    Run& run = (*runs)[i];
    Config config = o.config;
    config.seqslam.matcher = Matcher::kOpenSeqSlam;
    run.states = ReplayStateMachine(config, run.matches);
    Score(gt, &run);
  }
  return Status::Ok();
}

// Landmark confirmation, measured (issue 13 item 2): the state machine replayed with a
// frame counting as a match only when the 1D SURF recognition score (NN with RANSAC) of
// its strip against the matched route frame's strip reaches a threshold; a frame below it
// is "no match" (as a frame the matcher found nothing for). Sky runs with strips only.
Status LandmarkConfirmation(const EvalOptions& o, const Descriptors& rd, const Descriptors& qd,
                            const GroundTruth& gt, Run* run) {
  if (rd.strip_columns == 0 || rd.strip_columns != qd.strip_columns)
    return Status::Ok();
  SKYLOC_TRY_ASSIGN(const auto ref_features, StripFeatures(rd, o.config.heading));
  SKYLOC_TRY_ASSIGN(const auto query_features, StripFeatures(qd, o.config.heading));
  const dsp::HeadingOptions& options = o.config.heading.estimate;
  dsp::LandmarkMatcher matcher;
  if (const dsp::Surf1dError e = matcher.Init(options.max_features, options.matching);
      e != dsp::Surf1dError::kOk)
    return Status::Error(StatusCode::kInvalidArgument, "surf1d: %s", dsp::Surf1dErrorMessage(e));
  std::vector<float> score(run->matches.size(), 0.0f);
  for (std::size_t q = 0; q < run->matches.size(); ++q) {
    const dsp::SeqSlamMatch& m = run->matches[q];
    if (!m.valid || m.reference < 0 || m.reference >= rd.count)
      continue;
    dsp::LandmarkMatch lm;
    (void)matcher.Match(ref_features[static_cast<std::size_t>(m.reference)], query_features[q],
                        rd.strip_columns, &lm);
    score[q] = lm.model_found ? static_cast<float>(lm.ransac_score) : 0.0f;
  }
  Config config = o.config;
  config.seqslam.matcher = run->matcher;
  for (const double threshold : {25.0, 50.0, 100.0, 200.0, 400.0}) {
    std::vector<dsp::SeqSlamMatch> gated = run->matches;
    for (std::size_t q = 0; q < gated.size(); ++q)
      if (static_cast<double>(score[q]) < threshold)
        gated[q].valid = false;
    const std::vector<dsp::LocalisationState> states = ReplayStateMachine(config, gated);
    Run::Confirmation c;
    c.min_score = threshold;
    // Counted as Score counts them: over the frames the matcher gave a match (a frame
    // past the ends of OpenSeqSLAM's centred window has none but may still show LOCALISED).
    for (const int q : run->evaluated_queries) {
      const auto t = static_cast<std::size_t>(q);
      if (states[t] != dsp::LocalisationState::kLocalised)
        continue;
      ++c.localised;
      c.localised_correct += IsCorrect(gt, q, run->matches[t].reference) ? 1 : 0;
    }
    run->confirmation.push_back(c);
  }
  return Status::Ok();
}

// The heading of every correctly matched query frame against its matched reference frame,
// from the two frames' strips (dsp::HeadingEstimator, as the firmware), against the truth:
// the query pose's yaw minus the reference pose's. Needs strips and poses in both runs.
Status HeadingErrors(const EvalOptions& o, const Descriptors& ref_d, const Descriptors& query_d,
                     const drivers::Dataset& ref, const drivers::Dataset& query, Run* run) {
  if (ref_d.strip_columns == 0 || ref_d.strip_columns != query_d.strip_columns || !ref.has_poses ||
      !query.has_poses)
    return Status::Ok();
  const auto n = static_cast<std::size_t>(ref_d.strip_columns);
  dsp::HeadingEstimator estimator;
  if (const dsp::HeadingError e = estimator.Init(ref_d.strip_columns, o.config.heading.estimate);
      e != dsp::HeadingError::kOk)
    return Status::Error(StatusCode::kInvalidArgument, "[heading]: %s",
                         dsp::HeadingErrorMessage(e));
  std::vector<float> stored(n), test(n);
  std::vector<double> correlation, surf;  // signed errors, degrees
  int frames = 0;
  for (std::size_t k = 0; k < run->evaluated.size(); ++k) {
    if (!run->evaluated[k].correct)
      continue;
    const auto q = static_cast<std::size_t>(run->evaluated_queries[k]);
    const auto r = static_cast<std::size_t>(run->matches[q].reference);
    for (std::size_t j = 0; j < n; ++j) {
      stored[j] = ref_d.strips[r * n + j];
      test[j] = query_d.strips[q * n + j];
    }
    const double truth =
        dsp::WrapDegrees(query.frames[q].pose->yaw_deg - ref.frames[r].pose->yaw_deg);
    dsp::HeadingEstimate e;
    if (estimator.Estimate(stored, test, &e) != dsp::HeadingError::kOk)
      return Status::Error(StatusCode::kInternal, "heading of query frame %zu", q);
    ++frames;
    if (e.has_correlation)
      correlation.push_back(dsp::WrapDegrees(e.correlation_deg - truth));
    if (e.has_surf)
      surf.push_back(dsp::WrapDegrees(e.surf_deg - truth));
  }
  run->heading_evaluated = true;
  run->heading_correlation = dsp::SummariseHeadingErrors(correlation, frames);
  run->heading_surf = dsp::SummariseHeadingErrors(surf, frames);
  return Status::Ok();
}

// ---- Output files ------------------------------------------------------------------------

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

Status WriteMatchesCsv(const std::string& path, const std::vector<Run>& runs) {
  OutFile f;
  SKYLOC_TRY(f.Open(path));
  // New columns go last, so readers of the first seven keep working.
  std::fprintf(f.get(),
               "method,ds,query_index,reference_index,score,uniqueness,correct,matcher,state\n");
  for (const Run& run : runs) {
    for (std::size_t i = 0; i < run.evaluated_queries.size(); ++i) {
      const int q = run.evaluated_queries[i];
      const dsp::SeqSlamMatch& m = run.matches[static_cast<std::size_t>(q)];
      std::fprintf(f.get(), "%s,%d,%d,%d,%.6g,%.6g,%d,%s,%s\n", MethodName(run.method), run.ds, q,
                   m.reference, static_cast<double>(m.score), static_cast<double>(m.uniqueness),
                   run.evaluated[i].correct ? 1 : 0, run.matcher_name.c_str(),
                   dsp::LocalisationStateName(run.states[static_cast<std::size_t>(q)]));
    }
  }
  return f.Close();
}

Status WriteMetricsJson(const std::string& path, const EvalOptions& o, const GroundTruth& gt,
                        const std::vector<Run>& runs, int n_ref, int n_query) {
  OutFile f;
  SKYLOC_TRY(f.Open(path));
  std::FILE* out = f.get();
  std::fprintf(out, "{\n  \"reference\": %s,\n  \"query\": %s,\n", JsonString(o.reference).c_str(),
               JsonString(o.query).c_str());
  std::fprintf(out, "  \"reference_frames\": %d,\n  \"query_frames\": %d,\n", n_ref, n_query);
  std::fprintf(
      out, "  \"openseqslam_engine\": %s,\n",
      JsonString(o.streaming ? "streaming (trailing window)" : "batch (centred window)").c_str());
  std::fprintf(out, "  \"vanilla_precision_batch\": %s,\n",
               JsonString(o.vanilla_bytes ? "byte" : "float").c_str());
  std::fprintf(out, "  \"ground_truth\": %s,\n  \"frame_tolerance\": %d,\n",
               JsonString(gt.description).c_str(), o.frame_tolerance);
  std::fprintf(out, "  \"runs\": [\n");
  for (std::size_t i = 0; i < runs.size(); ++i) {
    const Run& r = runs[i];
    const dsp::PrSummary& s = r.summary;
    std::fprintf(out,
                 "    {\"method\": %s, \"matcher\": %s, \"ds\": %d, \"evaluated\": %d, "
                 "\"with_ground_truth\": %d, \"correct\": %d,\n",
                 JsonString(MethodName(r.method)).c_str(), JsonString(r.matcher_name).c_str(), r.ds,
                 s.evaluated, s.with_ground_truth, s.correct);
    std::fprintf(out, "     \"localised\": %d, \"localised_correct\": %d,\n", r.localised,
                 r.localised_correct);
    std::fprintf(out,
                 "     \"precision_at_100_recall\": %.6f, \"recall_at_100_precision\": %.6f, "
                 "\"auc\": %.6f,\n",
                 s.precision_at_full_recall, s.recall_at_full_precision, s.area_under_curve);
    if (r.heading_evaluated) {
      auto heading = [](const dsp::HeadingErrorSummary& h) {
        char text[160];
        std::snprintf(text, sizeof text,
                      "{\"frames\": %d, \"estimated\": %d, \"median_deg\": %.4f, "
                      "\"p90_deg\": %.4f, \"max_deg\": %.4f}",
                      h.frames, h.estimated, h.median_deg, h.p90_deg, h.max_deg);
        return std::string(text);
      };
      std::fprintf(out, "     \"heading\": {\"correlation\": %s, \"surf\": %s},\n",
                   heading(r.heading_correlation).c_str(), heading(r.heading_surf).c_str());
    } else {
      std::fprintf(out, "     \"heading\": null,\n");
    }
    std::fprintf(out, "     \"curve\": [");
    for (std::size_t k = 0; k < r.curve.size(); ++k) {
      const dsp::PrPoint& p = r.curve[k];
      std::fprintf(out, "%s{\"threshold\": %.6g, \"precision\": %.6f, \"recall\": %.6f}",
                   k == 0 ? "" : ", ", static_cast<double>(p.threshold), p.precision, p.recall);
    }
    std::fprintf(out, "]}%s\n", i + 1 < runs.size() ? "," : "");
  }
  std::fprintf(out, "  ]\n}\n");
  return f.Close();
}

// One curve per run, its summary in the legend; dashed ds = 1 and dotted ds >= 20 tell the
// sequence lengths of one method apart (docs/SEQSLAM.md).
std::string PrPlot(const std::vector<Run>& runs) {
  std::vector<PrCurve> curves;
  for (const Run& r : runs) {
    char summary[128];
    std::snprintf(summary, sizeof summary,
                  ": AUC %.3f, precision at 100%% recall %.3f, recall at 100%% precision %.3f",
                  r.summary.area_under_curve, r.summary.precision_at_full_recall,
                  r.summary.recall_at_full_precision);
    const LineDash dash =
        r.ds == 1 ? LineDash::kDashed : (r.ds >= 20 ? LineDash::kDotted : LineDash::kSolid);
    curves.push_back({r.label + summary, r.curve, dash});
  }
  return PrPlotSvg("Precision - recall (sweeping the uniqueness threshold)", curves);
}

// One panel per run, at most three a row.
std::string CorrespondencePlot(const std::vector<Run>& runs, const GroundTruth& gt, int n_ref) {
  std::vector<int> nearest;  // the truth line: the nearest reference frame of each query
  for (const dsp::TruthInterval& t : gt.reference)
    nearest.push_back(t.nearest);
  std::vector<CorrespondencePanel> panels;
  for (const Run& r : runs) {
    CorrespondencePanel panel{r.label, nearest, n_ref, {}};
    for (std::size_t k = 0; k < r.evaluated_queries.size(); ++k) {
      const int q = r.evaluated_queries[k];
      panel.matches.push_back(
          {q, r.matches[static_cast<std::size_t>(q)].reference, r.evaluated[k].correct});
    }
    panels.push_back(std::move(panel));
  }
  return CorrespondenceSvg(panels, 3);
}

Status Evaluate(EvalOptions o) {
  if (!o.config_file.empty()) {
    SKYLOC_TRY_ASSIGN(o.config, LoadConfigFile(o.config_file.c_str()));
  }
  if (o.max_advance)
    o.config.seqslam.filter.max_advance = *o.max_advance;
  if (o.keyframe_noise_factor)
    o.config.seqslam.filter.keyframe_noise_factor = static_cast<float>(*o.keyframe_noise_factor);
  if (o.bands) {
    if (o.config.descriptor.grid == GridPreset::kPaper)
      return Status::Error(StatusCode::kInvalidArgument,
                           "--bands %d: the configuration's [descriptor] grid = \"paper\" has 120 "
                           "bands; leave --bands out or choose another grid",
                           *o.bands);
    o.config.descriptor.bands = *o.bands;
    ResolveDescriptorGrid(&o.config.descriptor);  // a custom grid stays as it was
  }
  SKYLOC_TRY_ASSIGN(const drivers::Dataset ref, drivers::ReadDataset(o.reference));
  SKYLOC_TRY_ASSIGN(const drivers::Dataset query, drivers::ReadDataset(o.query));
  SKYLOC_TRY_ASSIGN(const GroundTruth gt, MakeGroundTruth(o, ref, query));
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) {
    return Status::Error(StatusCode::kUnavailable, "cannot create output folder %s: %s",
                         o.out.c_str(), ec.message().c_str());
  }
  std::vector<Run> runs;
  const int n_ref = static_cast<int>(ref.frames.size());
  const int n_query = static_cast<int>(query.frames.size());
  // The sky descriptors and their strips, computed once for the sky method and surf1d
  // (which reads only the strips: without sky, no floats are kept).
  const bool with_sky =
      std::find(o.methods.begin(), o.methods.end(), Method::kSky) != o.methods.end();
  std::optional<Descriptors> sky_ref, sky_query;
  const auto sky_descriptors = [&]() -> Status {
    if (sky_ref.has_value())
      return Status::Ok();
    std::fprintf(stderr, "skyloc eval: sky descriptors of %d + %d frames...\n", n_ref, n_query);
    DescriptorForms forms;
    forms.floats = with_sky;
    SKYLOC_TRY_ASSIGN(Descriptors rd, ComputeDescriptors(Method::kSky, o.reference, o, forms));
    SKYLOC_TRY_ASSIGN(Descriptors qd, ComputeDescriptors(Method::kSky, o.query, o, forms));
    sky_ref = std::move(rd);
    sky_query = std::move(qd);
    return Status::Ok();
  };
  for (const Method method : o.methods) {
    if (method == Method::kSurf1d) {
      SKYLOC_TRY(sky_descriptors());
      SKYLOC_TRY(RunSurf1dMethod(o, gt, *sky_ref, *sky_query, &runs));
      continue;
    }
    if (method == Method::kFabmap) {
      Run run;
      SKYLOC_TRY(RunFabmap(o, &run));
      run.states = ReplayStateMachine(o.config, run.matches);
      Score(gt, &run);
      runs.push_back(std::move(run));
      continue;
    }
    std::optional<Descriptors> vanilla_ref, vanilla_query;
    if (method == Method::kSky) {
      SKYLOC_TRY(sky_descriptors());
    } else {
      std::fprintf(stderr, "skyloc eval: %s descriptors of %d + %d frames...\n", MethodName(method),
                   n_ref, n_query);
      // Vanilla in bytes is read only by OpenSeqSLAM's batch engine; the route filter and
      // the streaming engine read floats.
      const bool batch_openseqslam =
          !o.streaming && std::find(o.matchers.begin(), o.matchers.end(), Matcher::kOpenSeqSlam) !=
                              o.matchers.end();
      DescriptorForms forms;
      forms.bytes = method == Method::kVanilla && o.vanilla_bytes && batch_openseqslam;
      forms.floats = !forms.bytes || o.matchers.size() > 1 || !batch_openseqslam;
      SKYLOC_TRY_ASSIGN(vanilla_ref, ComputeDescriptors(method, o.reference, o, forms));
      SKYLOC_TRY_ASSIGN(vanilla_query, ComputeDescriptors(method, o.query, o, forms));
    }
    const Descriptors& rd = method == Method::kSky ? *sky_ref : *vanilla_ref;
    const Descriptors& qd = method == Method::kSky ? *sky_query : *vanilla_query;
    for (const Matcher matcher : o.matchers) {
      for (const int ds : o.ds_list) {
        Run run;
        run.method = method;
        run.matcher = matcher;
        run.ds = ds;
        run.matcher_name = MatcherName(matcher);
        SKYLOC_TRY(RunMatcher(rd, qd, o, &run));
        Config config = o.config;
        config.seqslam.matcher = matcher;
        run.states = ReplayStateMachine(config, run.matches);
        Score(gt, &run);
        SKYLOC_TRY(HeadingErrors(o, rd, qd, ref, query, &run));
        SKYLOC_TRY(LandmarkConfirmation(o, rd, qd, gt, &run));
        runs.push_back(std::move(run));
      }
    }
  }
  SKYLOC_TRY(WriteMatchesCsv(o.out + "/matches.csv", runs));
  SKYLOC_TRY(WriteMetricsJson(o.out + "/metrics.json", o, gt, runs, n_ref, n_query));
  SKYLOC_TRY(WriteText(o.out + "/pr.svg", PrPlot(runs)));
  SKYLOC_TRY(WriteText(o.out + "/correspondence.svg", CorrespondencePlot(runs, gt, n_ref)));

  std::printf("%-8s %-12s %4s %9s %8s %13s %13s %7s %18s\n", "method", "matcher", "ds", "evaluated",
              "correct", "P@100%recall", "R@100%prec", "AUC", "LOCALISED correct");
  for (const Run& r : runs) {
    std::printf("%-8s %-12s %4d %9d %8d %13.3f %13.3f %7.3f %8d of %6d\n", MethodName(r.method),
                r.matcher_name.c_str(), r.ds, r.summary.evaluated, r.summary.correct,
                r.summary.precision_at_full_recall, r.summary.recall_at_full_precision,
                r.summary.area_under_curve, r.localised_correct, r.localised);
  }
  for (const Run& r : runs) {
    if (!r.heading_evaluated)
      continue;
    const dsp::HeadingErrorSummary& c = r.heading_correlation;
    const dsp::HeadingErrorSummary& s = r.heading_surf;
    std::printf(
        "heading %s %s ds %d, %d correctly matched frames: cross-correlation median %.2f, p90 "
        "%.2f deg (%d estimated); 1D SURF median %.2f, p90 %.2f deg (%d estimated)\n",
        MethodName(r.method), r.matcher_name.c_str(), r.ds, c.frames, c.median_deg, c.p90_deg,
        c.estimated, s.median_deg, s.p90_deg, s.estimated);
  }
  for (const Run& r : runs) {
    if (r.confirmation.empty())
      continue;
    std::printf("landmark confirmation %s %s ds %d: LOCALISED correct %d of %d without;",
                MethodName(r.method), r.matcher_name.c_str(), r.ds, r.localised_correct,
                r.localised);
    for (const Run::Confirmation& c : r.confirmation)
      std::printf(" score >= %.0f: %d of %d;", c.min_score, c.localised_correct, c.localised);
    std::printf("\n");
  }
  const bool openseqslam =
      std::find(o.matchers.begin(), o.matchers.end(), Matcher::kOpenSeqSlam) != o.matchers.end();
  std::printf("ground truth: %s;%s results in %s\n", gt.description.c_str(),
              openseqslam ? (o.streaming ? " openseqslam streaming;" : " openseqslam batch;") : "",
              o.out.c_str());
  return Status::Ok();
}

}  // namespace

dsp::SkyDescriptorOptions EvalSkyDescriptorOptions(Config config, const dsp::Lens& lens,
                                                   bool attitude_from_dataset,
                                                   std::optional<double> max_tilt_deg) {
  if (max_tilt_deg)
    config.attitude.max_tilt_deg = *max_tilt_deg;
  return SkyDescriptorOptionsFrom(config, lens, attitude_from_dataset);
}

int RunEval(std::span<char* const> args) {
  EvalOptions options;
  bool help = false;
  const int rc = ParseArgs(args, &options, &help);
  if (help) {
    std::fputs(kUsage, stdout);
    return kExitOk;
  }
  if (rc != kExitOk)
    return rc;
  // A file past RLIMIT_FSIZE is then a write error (EFBIG) reported naming the file, not a
  // silent death by signal.
  std::signal(SIGXFSZ, SIG_IGN);
  if (const Status out = CheckOutFolder(options); !out.ok()) {
    std::fprintf(stderr, "skyloc eval: %s\n", out.message());
    return kExitUsage;
  }
  const Status s = Evaluate(options);
  if (!s.ok()) {
    std::fprintf(stderr, "skyloc eval: %s\n", s.message());
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace skyloc::cli
