#include "skyloc/drivers/camera_file.h"

#include <fcntl.h>
#include <toml++/toml.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <initializer_list>
#include <iterator>
#include <limits>
#include <string>

#include "skyloc/drivers/dsp_status.h"
#include "skyloc/drivers/toml_keys.h"
#include "skyloc/drivers/toml_text.h"
#include "skyloc/platform/regular_file.h"

namespace skyloc::drivers {
namespace {

using dsp::LensModel;
using dsp::LensParams;

constexpr double kAny = std::numeric_limits<double>::infinity();

// Declares `keys` as the table's keys and refuses any other before anything is read: a
// misspelt key must not silently leave a default in place.
Status CheckKeys(TomlKeyReader* r, std::initializer_list<const char*> keys) {
  for (const char* key : keys)
    r->Has(key);
  return r->Finish();
}

// A key that does not apply to the chosen model is an error rather than ignored.
void RejectFor(TomlKeyReader* r, const char* model, std::initializer_list<const char*> keys) {
  for (const char* key : keys) {
    if (r->Has(key)) {
      char what[128];
      std::snprintf(what, sizeof what, "does not apply to model \"%s\": remove it", model);
      r->Invalid(key, what);
    }
  }
}

std::string Directory(const char* path) {
  const char* slash = std::strrchr(path, '/');
  if (slash == nullptr)
    return ".";
  if (slash == path)
    return "/";
  return std::string(path, static_cast<std::size_t>(slash - path));
}

Status ParseLens(const toml::table& lens, const char* source, const char* base_dir, LensParams* p) {
  TomlKeyReader r(&lens, "lens", source, TomlKeyNaming::kDotted);
  SKYLOC_TRY(CheckKeys(
      &r, {"model", "fov_deg", "centre", "radius_px", "fx", "fy", "k", "ocamcalib_file"}));
  constexpr const char* kModels[] = {"equidistant", "equisolid",       "kannala_brandt",
                                     "ocamcalib",   "equirectangular", "pinhole"};
  std::size_t model_index = std::size(kModels);
  r.Choice("model", kModels, &model_index);
  SKYLOC_TRY(r.status());
  if (model_index < std::size(kModels))
    dsp::ParseLensModel(kModels[model_index], &p->model);
  const char* model = dsp::LensModelName(p->model);
  r.Double("fov_deg", &p->fov_deg, -kAny, kAny);
  if (r.ok() && r.Has("fov_deg") && !(p->fov_deg > 0.0 && p->fov_deg <= 360.0))
    r.Invalid("fov_deg", "is out of range: use a field of view in (0, 360] degrees, e.g. 185");
  double centre[2] = {p->centre_x, p->centre_y};
  r.Numbers("centre", 2, centre);
  p->centre_x = centre[0];
  p->centre_y = centre[1];
  r.Double("radius_px", &p->radius_px, -kAny, kAny);
  if (r.ok() && r.Has("radius_px") && !(p->radius_px > 0.0))
    r.Invalid("radius_px", "must be a positive number of pixels");
  SKYLOC_TRY(r.status());

  switch (p->model) {
    case LensModel::kEquidistant:
    case LensModel::kEquisolid:
      RejectFor(&r, model, {"fx", "fy", "k", "ocamcalib_file"});
      break;
    case LensModel::kEquirectangular:
      RejectFor(&r, model, {"fov_deg", "centre", "radius_px", "fx", "fy", "k", "ocamcalib_file"});
      break;
    case LensModel::kPinhole: {
      RejectFor(&r, model, {"radius_px", "fx", "fy", "k", "ocamcalib_file"});
      SKYLOC_TRY(r.status());
      if (!r.Has("fov_deg"))
        return Status::Error(StatusCode::kInvalidArgument,
                             "%s: model \"pinhole\" needs lens.fov_deg (the horizontal field "
                             "of view across the image width, degrees, below 180)",
                             source);
      if (!(p->fov_deg < 180.0))
        r.Invalid("fov_deg",
                  "is out of range for a pinhole: use a horizontal field of view below 180 "
                  "degrees, e.g. 47.8");
      break;
    }
    case LensModel::kKannalaBrandt: {
      RejectFor(&r, model, {"ocamcalib_file"});
      r.Double("fx", &p->fx, -kAny, kAny);
      r.Double("fy", &p->fy, -kAny, kAny);
      SKYLOC_TRY(r.status());
      if (!r.Has("fx") || !r.Has("fy"))
        return Status::Error(StatusCode::kInvalidArgument,
                             "%s: model \"kannala_brandt\" needs lens.fx and lens.fy (pixels, "
                             "OpenCV's K[0][0] and K[1][1])",
                             source);
      if (!(p->fx > 0.0))
        r.Invalid("fx", "must be a positive focal length in pixels");
      if (!(p->fy > 0.0))
        r.Invalid("fy", "must be a positive focal length in pixels");
      r.Numbers("k", 4, p->k.data());
      break;
    }
    case LensModel::kOCamCalib: {
      RejectFor(&r, model, {"fx", "fy", "k", "centre"});
      SKYLOC_TRY(r.status());
      if (!r.Has("ocamcalib_file"))
        return Status::Error(StatusCode::kInvalidArgument,
                             "%s: model \"ocamcalib\" needs lens.ocamcalib_file = "
                             "\"calib_results.txt\" (the OCamCalib toolbox output)",
                             source);
      std::string file;
      r.String("ocamcalib_file", &file, true);
      if (r.ok() && file.empty())
        r.Invalid("ocamcalib_file", "must be a file name (relative to the camera file)");
      SKYLOC_TRY(r.status());
      const std::string path = file[0] == '/' ? file : std::string(base_dir) + "/" + file;
      Result<dsp::OCamCalibModel> ocam = LoadOCamCalibFile(path.c_str());
      if (!ocam.ok()) {
        Status s = ocam.status();
        return s.AddContext("%s: lens.ocamcalib_file", source);
      }
      p->ocam = *ocam;
      break;
    }
  }
  return r.status();
}

}  // namespace

Result<dsp::LensParams> GuessLensForImage(int width, int height, const char* image) {
  dsp::LensParams p;
  p.width = width;
  p.height = height;
  const double aspect = height > 0 ? static_cast<double>(width) / height : 0.0;
  if (std::fabs(aspect - 2.0) < 0.05) {
    p.model = dsp::LensModel::kEquirectangular;
  } else if (aspect > 0.74 && aspect < 1.35) {
    p.model = dsp::LensModel::kEquidistant;  // LensParams' defaults: 185 degrees, centred
  } else {
    return Status::Error(StatusCode::kInvalidArgument,
                         "cannot guess the lens of '%s' (%dx%d is neither square-ish nor 2:1): "
                         "pass --camera FILE.toml",
                         image, width, height);
  }
  return p;
}

Result<std::string> CameraFileText(const dsp::Lens& lens, const char* comment) {
  const dsp::LensParams& p = lens.params();
  if (p.model == dsp::LensModel::kOCamCalib)
    return Status::Error(StatusCode::kUnimplemented,
                         "an OCamCalib lens cannot be written out: copy its camera file and "
                         "calib_results.txt instead");
  char text[1024];
  int n = std::snprintf(text, sizeof text,
                        "# %s\n[image]\nwidth = %d\nheight = %d\n\n[lens]\nmodel = \"%s\"\n",
                        comment, p.width, p.height, dsp::LensModelName(p.model));
  if (p.model == dsp::LensModel::kPinhole) {
    n += std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n),
                       "fov_deg = %.9g\ncentre = [%.9g, %.9g]\n", p.fov_deg, lens.centre_x(),
                       lens.centre_y());
  } else if (p.model != dsp::LensModel::kEquirectangular) {
    n += std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n),
                       "fov_deg = %.9g\ncentre = [%.9g, %.9g]\nradius_px = %.9g\n", p.fov_deg,
                       lens.centre_x(), lens.centre_y(), lens.radius_px());
  }
  if (p.model == dsp::LensModel::kKannalaBrandt) {
    n += std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n),
                       "fx = %.17g\nfy = %.17g\nk = [%.17g, %.17g, %.17g, %.17g]\n", p.fx, p.fy,
                       p.k[0], p.k[1], p.k[2], p.k[3]);
  }
  std::snprintf(text + n, sizeof text - static_cast<std::size_t>(n),
                "\n[mount]\nroll_deg = %.9g\npitch_deg = %.9g\nyaw_deg = %.9g\n", p.roll_deg,
                p.pitch_deg, p.yaw_deg);
  return std::string(text);
}

Status InitLens(const dsp::LensParams& params, const char* source, dsp::Lens* lens) {
  const dsp::LensError e = lens->Init(params);
  if (e == dsp::LensError::kOk)
    return Status::Ok();
  return DspStatus(e, "%s: invalid %s lens", source, dsp::LensModelName(params.model));
}

Result<dsp::LensParams> ParseCameraFile(std::string_view text, const char* source,
                                        const char* base_dir) {
  SKYLOC_TRY_ASSIGN(const toml::table root, ParseTomlText(text, source));
  TomlKeyReader top(&root, "top level", source, TomlKeyNaming::kDotted);
  SKYLOC_TRY(CheckKeys(&top, {"image", "lens", "mount"}));
  for (const char* name : {"image", "lens", "mount"}) {
    const toml::node* node = root.get(name);
    if (node != nullptr && !node->is_table())
      return Status::Error(StatusCode::kInvalidArgument, "%s:%u: '%s' must be a table: [%s]",
                           source, static_cast<unsigned>(node->source().begin.line), name, name);
  }
  LensParams p;
  const toml::table* image = root.get_as<toml::table>("image");
  if (image == nullptr)
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s: missing [image] with width and height (pixels)", source);
  TomlKeyReader r(image, "image", source, TomlKeyNaming::kDotted);
  SKYLOC_TRY(CheckKeys(&r, {"width", "height"}));
  r.Int("width", &p.width, 1, 65534);
  r.Int("height", &p.height, 1, 65534);
  SKYLOC_TRY(r.status());
  if (!r.Has("width") || !r.Has("height"))
    return Status::Error(StatusCode::kInvalidArgument,
                         "%s: [image] needs both width and height (pixels)", source);

  if (const toml::table* lens = root.get_as<toml::table>("lens"))
    SKYLOC_TRY(ParseLens(*lens, source, base_dir, &p));

  if (const toml::table* mount = root.get_as<toml::table>("mount")) {
    TomlKeyReader m(mount, "mount", source, TomlKeyNaming::kDotted);
    SKYLOC_TRY(CheckKeys(&m, {"roll_deg", "pitch_deg", "yaw_deg"}));
    m.Double("roll_deg", &p.roll_deg, -360, 360);
    m.Double("pitch_deg", &p.pitch_deg, -360, 360);
    m.Double("yaw_deg", &p.yaw_deg, -360, 360);
    SKYLOC_TRY(m.status());
  }
  dsp::Lens lens;
  SKYLOC_TRY(InitLens(p, source, &lens));
  return p;
}

Result<dsp::LensParams> LoadCameraFile(const char* path) {
  // A FIFO or device named as the camera file is refused, not waited on.
  UniqueFd fd;
  SKYLOC_TRY(OpenRegularFile(path, O_RDONLY, "camera file", &fd));
  std::FILE* f = ::fdopen(fd.get(), "rb");
  if (f == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot open camera file '%s'", path);
  }
  (void)fd.release();  // the FILE owns it now
  std::string text;
  char buffer[4096];
  std::size_t n = 0;
  while ((n = std::fread(buffer, 1, sizeof buffer, f)) > 0) {
    text.append(buffer, n);
    if (text.size() > (std::size_t{1} << 20)) {
      std::fclose(f);
      return Status::Error(StatusCode::kInvalidArgument,
                           "camera file '%s' is larger than 1 MiB: is it the right file?", path);
    }
  }
  const bool read_error = std::ferror(f) != 0;
  const int saved = errno;
  std::fclose(f);
  if (read_error)
    return Status::FromErrno(saved, "cannot read camera file '%s'", path);
  return ParseCameraFile(text, path, Directory(path).c_str());
}

Result<dsp::OCamCalibModel> LoadOCamCalibFile(const char* path) {
  std::FILE* f = std::fopen(path, "r");
  if (f == nullptr) {
    const int saved = errno;
    return Status::FromErrno(saved, "cannot open OCamCalib file '%s'", path);
  }
  dsp::OCamCalibModel m;
  // The toolbox writes five data lines in this order, each after a '#' comment.
  enum Field { kSs, kInvpol, kCentre, kAffine, kSize, kDone };
  const char* const kExpected[] = {"the ss polynomial: a count then that many coefficients",
                                   "the invpol polynomial: a count then that many coefficients",
                                   "the centre: row and column", "the affine parameters c d e",
                                   "the image size: height width"};
  int field = kSs;
  char line[8192];
  unsigned line_number = 0;
  Status status;
  while (field != kDone && std::fgets(line, sizeof line, f) != nullptr) {
    ++line_number;
    const char* p = line;
    while (*p == ' ' || *p == '\t' || *p == '\r' || *p == '\n')
      ++p;
    if (*p == '\0' || *p == '#')
      continue;
    double values[dsp::OCamCalibModel::kMaxTerms + 1];
    int count = 0;
    for (char* end = nullptr; count <= dsp::OCamCalibModel::kMaxTerms; ++count) {
      const double v = std::strtod(p, &end);
      if (end == p)
        break;
      values[count] = v;
      p = end;
    }
    const auto bad = [&](const char* why) {
      return Status::Error(StatusCode::kInvalidArgument,
                           "OCamCalib file '%s' line %u: expected %s (%s); re-export "
                           "calib_results.txt from the toolbox",
                           path, line_number, kExpected[field], why);
    };
    if (field == kSs || field == kInvpol) {
      const int n = count > 0 ? static_cast<int>(values[0]) : -1;
      if (count < 1 || values[0] != n || n < 1 || n > dsp::OCamCalibModel::kMaxTerms) {
        status = bad("the count is missing or outside 1..32");
        break;
      }
      if (count - 1 != n) {
        status = bad("the count does not match the coefficients");
        break;
      }
      auto& target = field == kSs ? m.ss : m.invpol;
      for (int i = 0; i < n; ++i)
        target[static_cast<std::size_t>(i)] = values[i + 1];
      (field == kSs ? m.ss_count : m.invpol_count) = n;
    } else if (field == kCentre) {
      if (count != 2) {
        status = bad("need 2 numbers");
        break;
      }
      m.row_centre = values[0];
      m.column_centre = values[1];
    } else if (field == kAffine) {
      if (count != 3) {
        status = bad("need 3 numbers");
        break;
      }
      m.c = values[0];
      m.d = values[1];
      m.e = values[2];
    } else if (field == kSize) {
      if (count != 2 || values[0] < 1 || values[1] < 1 || values[0] > 65534 || values[1] > 65534) {
        status = bad("need 2 positive whole numbers");
        break;
      }
      m.height = static_cast<int>(values[0]);
      m.width = static_cast<int>(values[1]);
    }
    ++field;
  }
  std::fclose(f);
  if (!status.ok())
    return status;
  // The image size line is optional (older toolbox versions do not write it).
  if (field < kSize)
    return Status::Error(StatusCode::kInvalidArgument,
                         "OCamCalib file '%s' ends early: expected %s; re-export "
                         "calib_results.txt from the toolbox",
                         path, kExpected[field]);
  return m;
}

}  // namespace skyloc::drivers
