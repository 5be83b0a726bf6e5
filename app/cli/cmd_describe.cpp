// skyloc describe: the sky descriptor of image files, for inspecting what the pipeline
// sees. Every image is processed even when an earlier one fails; the exit code is 1 if
// any image failed, so scripts notice, and 2 for a bad command line (nothing processed).
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli/commands.h"
#include "cli/describe.h"
#include "cli/options.h"
#include "firmware/descriptor.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dsp_status.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"

namespace skyloc::cli {
namespace {

constexpr char kDescription[] =
    "Prints, per image (PNG, PGM, PPM), the segmentation threshold, the sky fraction and\n"
    "the spherical-harmonic amplitude spectrum a_0..a_(L-1), as the robot describes a\n"
    "frame (firmware::SkyDescriptorOptionsFrom): the descriptor of --config (default: the\n"
    "built-in one, 120 bands on the oversampled grid, unit_l2), its [segmentation] and,\n"
    "when [attitude] kind is not none, the gravity-aligned cap as if level. --bands,\n"
    "--grid and --normalisation replace the configuration's. The paper's descriptor is\n"
    "--bands 120 --grid auto --normalisation none.\n"
    "\n"
    "Exit status: 0 all images described, 1 some image failed (the others are still\n"
    "described), 2 bad command line.\n";

struct Options {
  std::string camera;
  std::string config_path;
  DescribeDescriptorFlags descriptor;
  bool json = false;
  std::optional<dsp::LensModel> lens;
  std::optional<double> fov_deg;
  std::optional<double> centre_x, centre_y;
  std::optional<double> radius_px;
  std::vector<std::string> images;
};

// Parses and checks the command line; kRun or the outcome to exit with.
ParseOutcome ParseArgs(std::span<char* const> args, Options* o) {
  OptionTable t("describe", "[options] IMAGE...", kDescription);
  t.Text("--camera", "FILE.toml",
         "camera file (docs/CAMERA_FILE.md). Without one, a square-ish image is an equidistant "
         "185-degree fisheye filling the image circle and a 2:1 image an equirectangular "
         "panorama",
         &o->camera);
  t.Text("--config", "FILE.toml",
         "the firmware configuration whose [descriptor], [segmentation] and [attitude] "
         "describe the images (default: the built-in defaults)",
         &o->config_path);
  static_assert(firmware::DescriptorConfig{}.bands == 120, "the help states the default bands");
  t.Int("--bands", "L", "number of bands (default: [descriptor] bands, 120)", 1, dsp::kMaxShBands,
        &o->descriptor.bands);
  AddDescriptorChoices(&t, &o->descriptor.grid, &o->descriptor.normalisation);
  t.Flag("--json", "one JSON object per line: file, threshold, sky_fraction, amplitudes", &o->json);
  t.Choice("--lens", "override the lens model (other models need a camera file)",
           {{"equidistant", dsp::LensModel::kEquidistant},
            {"equisolid", dsp::LensModel::kEquisolid},
            {"equirectangular", dsp::LensModel::kEquirectangular}},
           &o->lens);
  t.Number("--fov", "DEG", "override the field of view", {0, 360, true, false}, &o->fov_deg);
  // --centre X,Y (or --center): kept as a pair until both are read, then optional.
  double centre_x = 0, centre_y = 0;
  const auto finite = [](double, double) { return true; };
  t.NumberPair("--centre", "X,Y", "override the image circle's centre (pixels)",
               "X,Y in pixels (e.g. 319.5,239.5)", finite, &centre_x, &centre_y);
  t.NumberPair("--center", "X,Y", "as --centre", "X,Y in pixels (e.g. 319.5,239.5)", finite,
               &centre_x, &centre_y);
  t.Number("--radius", "PX", "override the image circle's radius (pixels)", kPositive,
           &o->radius_px);
  t.Positional("IMAGE", "the images to describe", 0, std::numeric_limits<std::size_t>::max(),
               &o->images);
  if (const ParseOutcome outcome = t.Parse(args); outcome != ParseOutcome::kRun)
    return outcome;
  if (o->images.empty())
    return t.Refuse("no image given: pass one or more PNG/PGM/PPM files");
  if (t.Given("--centre") && t.Given("--center"))
    return t.Refuse("give --centre or --center, not both");
  if (t.Given("--centre") || t.Given("--center")) {
    o->centre_x = centre_x;
    o->centre_y = centre_y;
  }
  return ParseOutcome::kRun;
}

// The lens for an image of this size: the camera file's, or a guess from the shape.
Result<dsp::LensParams> LensFor(const Options& o, const dsp::LensParams* camera, int width,
                                int height, const char* image_path) {
  dsp::LensParams p;
  if (camera != nullptr) {
    p = *camera;
    if (p.width != width || p.height != height)
      return Status::Error(StatusCode::kInvalidArgument,
                           "'%s' is %dx%d but camera file '%s' describes %dx%d images: use the "
                           "camera file made for this camera",
                           image_path, width, height, o.camera.c_str(), p.width, p.height);
  } else if (Result<dsp::LensParams> guess = drivers::GuessLensForImage(width, height, image_path);
             guess.ok()) {
    p = *guess;
  } else if (!o.lens) {
    return Status::Error(StatusCode::kInvalidArgument, "%s or --lens", guess.status().message());
  } else {
    p.width = width;  // --lens says what the shape could not
    p.height = height;
  }
  if (o.lens)
    p.model = *o.lens;
  if (o.fov_deg)
    p.fov_deg = *o.fov_deg;
  if (o.centre_x) {
    p.centre_x = *o.centre_x;
    p.centre_y = *o.centre_y;
  }
  if (o.radius_px)
    p.radius_px = *o.radius_px;
  return p;
}

void PrintJsonString(const char* s) {
  std::putchar('"');
  for (; *s != '\0'; ++s) {
    const auto c = static_cast<unsigned char>(*s);
    if (c == '"' || c == '\\')
      std::printf("\\%c", c);
    else if (c < 0x20)
      std::printf("\\u%04x", c);
    else
      std::putchar(c);
  }
  std::putchar('"');
}

void PrintResult(const Options& o, const char* path, const dsp::SegmentationResult& seg,
                 std::span<const float> amplitudes) {
  if (o.json) {
    std::printf("{\"file\":");
    PrintJsonString(path);
    std::printf(",\"threshold\":%d,\"sky_fraction\":%.6f,\"amplitudes\":[", seg.threshold,
                seg.sky_fraction);
    for (std::size_t l = 0; l < amplitudes.size(); ++l)
      std::printf("%s%.9g", l == 0 ? "" : ",", static_cast<double>(amplitudes[l]));
    std::printf("]}\n");
  } else {
    std::printf("%s\n  threshold %d, sky fraction %.4f\n  amplitudes", path, seg.threshold,
                seg.sky_fraction);
    for (std::size_t l = 0; l < amplitudes.size(); ++l)
      std::printf("%s%.6g", l % 8 == 0 ? "\n   " : " ", static_cast<double>(amplitudes[l]));
    std::printf("\n");
  }
  std::fflush(stdout);
}

bool SameLens(const dsp::LensParams& a, const dsp::LensParams& b) {
  const auto same = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  const dsp::OCamCalibModel& oa = a.ocam;
  const dsp::OCamCalibModel& ob = b.ocam;
  return a.model == b.model && a.width == b.width && a.height == b.height &&
         same(a.centre_x, b.centre_x) && same(a.centre_y, b.centre_y) &&
         same(a.radius_px, b.radius_px) && a.fov_deg == b.fov_deg && a.fx == b.fx && a.fy == b.fy &&
         a.k == b.k && a.roll_deg == b.roll_deg && a.pitch_deg == b.pitch_deg &&
         a.yaw_deg == b.yaw_deg && oa.ss == ob.ss && oa.ss_count == ob.ss_count &&
         oa.invpol == ob.invpol && oa.invpol_count == ob.invpol_count &&
         oa.row_centre == ob.row_centre && oa.column_centre == ob.column_centre && oa.c == ob.c &&
         oa.d == ob.d && oa.e == ob.e && oa.width == ob.width && oa.height == ob.height;
}

}  // namespace

firmware::Config DescribeConfig(firmware::Config config, const DescribeDescriptorFlags& flags) {
  if (flags.bands)
    config.descriptor.bands = *flags.bands;
  if (flags.grid)
    config.descriptor.grid = *flags.grid;
  if (flags.normalisation)
    config.descriptor.normalisation = *flags.normalisation;
  firmware::ResolveDescriptorGrid(&config.descriptor);
  return config;
}

Status InitDescribeDescriptor(const firmware::Config& config, const dsp::Lens& lens,
                              dsp::SkyDescriptor* descriptor) {
  const dsp::SkyDescriptorOptions options = firmware::SkyDescriptorOptionsFrom(
      config, lens, config.attitude.kind != firmware::AttitudeKind::kNone);
  if (const dsp::DescriptorError e = descriptor->Init(lens, options); !e.ok())
    return drivers::DspStatus(e, "sky descriptor");
  return Status::Ok();
}

namespace {

int DescribeImages(const Options& o) {
  std::optional<dsp::LensParams> camera;
  if (!o.camera.empty()) {
    Result<dsp::LensParams> loaded = drivers::LoadCameraFile(o.camera.c_str());
    if (!loaded.ok())
      return Failed("describe", loaded.status());
    camera = *loaded;
  }
  firmware::Config base = firmware::DefaultConfig();
  if (!o.config_path.empty()) {
    Result<firmware::Config> loaded = firmware::LoadConfigFile(o.config_path.c_str());
    if (!loaded.ok())
      return Failed("describe", loaded.status());
    base = *std::move(loaded);
  }
  const firmware::Config config = DescribeConfig(base, o.descriptor);
  std::vector<float> amplitudes(static_cast<std::size_t>(config.descriptor.bands));
  dsp::SkyDescriptor descriptor;
  std::optional<dsp::LensParams> descriptor_lens;  // what `descriptor` was built for

  int failed = 0;
  for (const std::string& image_path : o.images) {
    const char* path = image_path.c_str();
    const auto fail = [&](const Status& s) {
      std::fprintf(stderr, "skyloc describe: %s\n", s.message());
      ++failed;
    };
    Result<drivers::OwnedImage> image = drivers::LoadImage(path);
    if (!image.ok()) {
      fail(image.status());
      continue;
    }
    Result<dsp::LensParams> params =
        LensFor(o, camera ? &*camera : nullptr, image->width(), image->height(), path);
    if (!params.ok()) {
      fail(params.status());
      continue;
    }
    // Tables are rebuilt only when the lens changes (images of one camera share them).
    if (!descriptor_lens || !SameLens(*descriptor_lens, *params)) {
      descriptor_lens.reset();
      dsp::Lens lens;
      if (Status s = drivers::InitLens(
              *params, !o.camera.empty() ? o.camera.c_str() : "--lens/--fov/--centre/--radius",
              &lens);
          !s.ok()) {
        fail(s.AddContext("'%s'", path));
        continue;
      }
      if (Status s = InitDescribeDescriptor(config, lens, &descriptor); !s.ok()) {
        fail(s.AddContext("'%s'", path));
        continue;
      }
      descriptor_lens = *params;
    }
    dsp::SegmentationResult segmentation;
    if (const dsp::DescriptorError e = descriptor.Compute(image->view(), amplitudes, &segmentation);
        !e.ok()) {
      fail(drivers::DspStatus(e, "'%s'", path));
      continue;
    }
    PrintResult(o, path, segmentation, amplitudes);
  }
  if (failed > 0) {
    std::fprintf(stderr, "skyloc describe: %d of %zu images failed\n", failed, o.images.size());
    return kExitFailure;
  }
  return kExitOk;
}

}  // namespace

int RunDescribe(std::span<char* const> args) {
  return RunParsed(args, ParseArgs, DescribeImages);
}

}  // namespace skyloc::cli
