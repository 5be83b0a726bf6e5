// skyloc describe: the sky descriptor of image files, for inspecting what the pipeline
// sees. Every image is processed even when an earlier one fails; the exit code is 1 if
// any image failed, so scripts notice, and 2 for a bad command line (nothing processed).
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <optional>
#include <vector>

#include "cli/commands.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/sky_descriptor.h"

namespace skyloc::cli {
namespace {

constexpr char kUsage[] =
    "usage: skyloc describe [--camera FILE.toml] [--bands L] [--grid default|oversampled|paper]\n"
    "                       [--json]\n"
    "                       [--lens equidistant|equisolid|equirectangular] [--fov DEG]\n"
    "                       [--centre X,Y] [--radius PX] IMAGE...\n"
    "\n"
    "Prints, per image (PNG, PGM, PPM), the Otsu threshold, the sky fraction and the\n"
    "spherical-harmonic amplitude spectrum a_0..a_(L-1).\n"
    "\n"
    "  --camera FILE  camera file (docs/CAMERA_FILE.md). Without one, a square-ish image is\n"
    "                 an equidistant 185-degree fisheye filling the image circle and a 2:1\n"
    "                 image an equirectangular panorama\n"
    "  --bands L      number of bands, 1..512 (default 120)\n"
    "  --grid G       'default' (the minimal unaliased grid for L bands), 'oversampled' (the\n"
    "                 firmware's: the unaliased grid for 1.5 L; with --bands 64 the\n"
    "                 firmware's default descriptor before its normalisation) or 'paper'\n"
    "                 (2000 points)\n"
    "  --json         one JSON object per line: file, threshold, sky_fraction, amplitudes\n"
    "  --lens, --fov, --centre, --radius  override the camera file or the guess\n"
    "\n"
    "Exit status: 0 all images described, 1 some image failed (the others are still\n"
    "described), 2 bad command line.\n";

struct Options {
  const char* camera = nullptr;
  int bands = 120;
  enum class Grid : std::uint8_t { kDefault, kOversampled, kPaper } grid = Grid::kDefault;
  bool json = false;
  std::optional<dsp::LensModel> lens;
  std::optional<double> fov_deg;
  std::optional<double> centre_x, centre_y;
  std::optional<double> radius_px;
  std::vector<const char*> images;
};

int Usage(std::string_view what, std::string_view value = {}) {
  return UsageError("describe", what, value);
}

// Returns kExitOk when parsed, else the exit code (help: kExitOk via `done`).
int ParseArgs(std::span<char* const> args, Options* o, bool* done) {
  *done = false;
  for (std::size_t i = 0; i < args.size(); ++i) {
    const char* a = args[i];
    const auto value = [&]() -> const char* { return i + 1 < args.size() ? args[++i] : nullptr; };
    if (IsHelpFlag(a)) {
      std::fputs(kUsage, stdout);
      *done = true;
      return kExitOk;
    }
    if (std::strcmp(a, "--json") == 0) {
      o->json = true;
    } else if (std::strcmp(a, "--camera") == 0) {
      if ((o->camera = value()) == nullptr)
        return Usage("%s needs a camera file (TOML)", a);
    } else if (std::strcmp(a, "--bands") == 0) {
      const char* v = value();
      double bands = 0;
      if (v == nullptr || !ParseFiniteDouble(v, &bands) || bands != std::floor(bands) ||
          bands < 1 || bands > dsp::kMaxShBands)
        return Usage("--bands needs a whole number from 1 to 512, not '%s'", v ? v : "");
      o->bands = static_cast<int>(bands);
    } else if (std::strcmp(a, "--grid") == 0) {
      const char* v = value();
      if (v != nullptr && std::strcmp(v, "paper") == 0)
        o->grid = Options::Grid::kPaper;
      else if (v != nullptr && std::strcmp(v, "oversampled") == 0)
        o->grid = Options::Grid::kOversampled;
      else if (v != nullptr && std::strcmp(v, "default") == 0)
        o->grid = Options::Grid::kDefault;
      else
        return Usage("--grid must be 'default', 'oversampled' or 'paper', not '%s'", v ? v : "");
    } else if (std::strcmp(a, "--lens") == 0) {
      const char* v = value();
      dsp::LensModel model;
      if (v == nullptr || !dsp::ParseLensModel(v, &model) ||
          model == dsp::LensModel::kKannalaBrandt || model == dsp::LensModel::kOCamCalib ||
          model == dsp::LensModel::kPinhole)
        return Usage(
            "--lens must be equidistant, equisolid or equirectangular (other "
            "models need a camera file), not '%s'",
            v ? v : "");
      o->lens = model;
    } else if (std::strcmp(a, "--fov") == 0) {
      const char* v = value();
      double fov = 0;
      if (v == nullptr || !ParseFiniteDouble(v, &fov) || !(fov > 0 && fov <= 360))
        return Usage("--fov needs a field of view in (0, 360] degrees, not '%s'", v ? v : "");
      o->fov_deg = fov;
    } else if (std::strcmp(a, "--centre") == 0 || std::strcmp(a, "--center") == 0) {
      const char* v = value();
      double x = 0, y = 0;
      char* end = nullptr;
      if (v == nullptr || !ParseFiniteDouble(v, &x, &end) || *end != ',' ||
          !ParseFiniteDouble(end + 1, &y))
        return Usage("--centre needs X,Y in pixels (e.g. 319.5,239.5), not '%s'", v ? v : "");
      o->centre_x = x;
      o->centre_y = y;
    } else if (std::strcmp(a, "--radius") == 0) {
      const char* v = value();
      double r = 0;
      if (v == nullptr || !ParseFiniteDouble(v, &r) || !(r > 0))
        return Usage("--radius needs a positive image-circle radius in pixels, not '%s'",
                     v ? v : "");
      o->radius_px = r;
    } else if (a[0] == '-' && a[1] != '\0') {
      return Usage("unknown option '%s'", a);
    } else {
      o->images.push_back(a);
    }
  }
  if (o->images.empty())
    return Usage("no image given: pass one or more PNG/PGM/PPM files");
  return kExitOk;
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
                           image_path, width, height, o.camera, p.width, p.height);
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

int RunDescribe(std::span<char* const> args) {
  Options o;
  bool done = false;
  if (const int rc = ParseArgs(args, &o, &done); rc != kExitOk || done)
    return rc;

  std::optional<dsp::LensParams> camera;
  if (o.camera != nullptr) {
    Result<dsp::LensParams> loaded = drivers::LoadCameraFile(o.camera);
    if (!loaded.ok()) {
      std::fprintf(stderr, "skyloc describe: %s\n", loaded.status().message());
      return kExitFailure;
    }
    camera = *loaded;
  }

  dsp::SkyDescriptorOptions descriptor_options;
  descriptor_options.bands = o.bands;
  if (o.grid == Options::Grid::kPaper)
    descriptor_options.grid = dsp::PaperShGridConfig();
  else if (o.grid == Options::Grid::kOversampled)
    descriptor_options.grid = dsp::OversampledShGridConfig(o.bands);
  std::vector<float> amplitudes(static_cast<std::size_t>(o.bands));
  dsp::SkyDescriptor descriptor;
  std::optional<dsp::LensParams> descriptor_lens;  // what `descriptor` was built for

  int failed = 0;
  for (const char* path : o.images) {
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
              *params, o.camera ? o.camera : "--lens/--fov/--centre/--radius", &lens);
          !s.ok()) {
        fail(s.AddContext("'%s'", path));
        continue;
      }
      if (const dsp::DescriptorError e = descriptor.Init(lens, descriptor_options); !e.ok()) {
        fail(Status::Error(StatusCode::kInvalidArgument, "'%s': %s", path, e.message));
        continue;
      }
      descriptor_lens = *params;
    }
    dsp::SegmentationResult segmentation;
    if (const dsp::DescriptorError e = descriptor.Compute(image->view(), amplitudes, &segmentation);
        !e.ok()) {
      fail(Status::Error(StatusCode::kInvalidArgument, "'%s': %s", path, e.message));
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

}  // namespace skyloc::cli
