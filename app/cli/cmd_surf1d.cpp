// skyloc surf1d: the second method of the brief on two images, for a user to see what 1D
// SURF finds and how far apart in heading two views are (docs/SURF1D.md). Reads each
// image's horizon strip through the lens, detects 1D SURF features, matches them (ratio
// test, RANSAC on x_B = b_s x_A + b_d) and reports both recognition scores and the
// heading, by RANSAC and by circular correlation of the strips; --plot draws the two strips
// and the matches as the paper's Fig. 2.
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "cli/commands.h"
#include "skyloc/drivers/camera_file.h"
#include "skyloc/drivers/dsp_status.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/dsp/horizon_strip.h"
#include "skyloc/dsp/lens.h"
#include "skyloc/dsp/strip_alignment.h"
#include "skyloc/dsp/surf1d.h"

namespace skyloc::cli {
namespace {

constexpr char kDescription[] =
    "1D SURF (Anderson et al. 2012, docs/SURF1D.md) between two images of one camera: the\n"
    "horizon strip of each (the mean of a band of elevations, every azimuth), its features,\n"
    "the matches (nearest-neighbour ratio test, RANSAC on x_B = b_s x_A + b_d), both\n"
    "recognition scores (sum of 1/distance over the matches, and over RANSAC's inliers)\n"
    "and the heading of B relative to A, by RANSAC's inliers and by circular correlation\n"
    "of the whole strips. Without --camera, a square-ish image is an equidistant\n"
    "185-degree fisheye filling the short side and a 2:1 image an equirectangular\n"
    "panorama.\n"
    "Exit status: 0 done, 1 an image or the camera file could not be used, 2 bad command\n"
    "line.\n";

constexpr int kMaxFeatures = 1024;

struct Options {
  std::vector<std::string> images;  // IMAGE_A IMAGE_B
  std::string camera;
  std::string plot;
  dsp::HorizonStripOptions strip;
  dsp::Surf1dOptions surf;
};

// Parses and checks the command line; kRun or the outcome to exit with.
ParseOutcome ParseArgs(std::span<char* const> args, Options* o) {
  OptionTable t("surf1d", "IMAGE_A IMAGE_B [options]", kDescription);
  t.Positional("IMAGE_A IMAGE_B", "the two images", 0, 2, &o->images);
  t.Text("--camera", "FILE", "camera file (docs/CAMERA_FILE.md)", &o->camera);
  t.NumberPair(
      "--elevation", "MIN,MAX", "the strip's band of elevations, degrees (default 0,20)",
      "MIN,MAX degrees, -90 <= MIN <= MAX <= 90",
      [](double lo, double hi) { return lo >= -90 && lo <= hi && hi <= 90; },
      &o->strip.elevation_min_deg, &o->strip.elevation_max_deg);
  t.Int("--columns", "N", "strip length over 360 degrees (default 360)", 64, 4096,
        &o->strip.n_azimuth);
  double threshold = static_cast<double>(o->surf.threshold);
  t.Number("--threshold", "T", "1D SURF's response threshold (default 2)", {0, 1000}, &threshold);
  t.Text("--plot", "FILE.svg", "draw both strips, their features and the matches (inliers green)",
         &o->plot);
  if (const ParseOutcome outcome = t.Parse(args); outcome != ParseOutcome::kRun)
    return outcome;
  o->surf.threshold = static_cast<float>(threshold);
  if (o->images.size() != 2)
    return t.Refuse("give two images: IMAGE_A IMAGE_B");
  return ParseOutcome::kRun;
}

// The lens of an image: the camera file's (its size must match), or describe's guess.
Result<dsp::LensParams> LensFor(const Options& o, int width, int height, const char* path) {
  if (!o.camera.empty()) {
    SKYLOC_TRY_ASSIGN(dsp::LensParams p, drivers::LoadCameraFile(o.camera.c_str()));
    if (p.width != width || p.height != height)
      return Status::Error(StatusCode::kInvalidArgument,
                           "'%s' is %dx%d but camera file '%s' describes %dx%d images: use the "
                           "camera file made for this camera",
                           path, width, height, o.camera.c_str(), p.width, p.height);
    return p;
  }
  return drivers::GuessLensForImage(width, height, path);
}

struct View {
  const char* path = nullptr;
  std::vector<float> strip;
  std::vector<dsp::Surf1dFeature> features;
};

Status Extract(const Options& o, const char* path, dsp::Surf1d* surf, View* view) {
  SKYLOC_TRY_ASSIGN(const drivers::OwnedImage image, drivers::LoadImage(path));
  SKYLOC_TRY_ASSIGN(const dsp::LensParams params, LensFor(o, image.width(), image.height(), path));
  dsp::Lens lens;
  SKYLOC_TRY(
      drivers::InitLens(params, !o.camera.empty() ? o.camera.c_str() : "the guessed lens", &lens));
  dsp::HorizonStrip strip;
  if (const dsp::HorizonStripError e = strip.Init(lens, o.strip); e != dsp::HorizonStripError::kOk)
    return drivers::DspStatus(e, "%s: horizon strip", path);
  view->path = path;
  view->strip.assign(static_cast<std::size_t>(strip.n_azimuth()), 0.0f);
  if (const dsp::HorizonStripError e = strip.Extract(image.view(), view->strip);
      e != dsp::HorizonStripError::kOk)
    return drivers::DspStatus(e, "%s: horizon strip", path);
  if (surf->n() != strip.n_azimuth()) {
    if (const dsp::Surf1dError e = surf->Init(strip.n_azimuth(), o.surf);
        e != dsp::Surf1dError::kOk)
      return drivers::DspStatus(e, "1D SURF");
  }
  view->features.resize(kMaxFeatures);
  int count = 0;
  if (const dsp::Surf1dError e = surf->Detect(view->strip, view->features, &count);
      e != dsp::Surf1dError::kOk)
    return drivers::DspStatus(e, "%s: 1D SURF", path);
  view->features.resize(static_cast<std::size_t>(count));
  std::printf(
      "%s: %dx%d, strip of %d columns (elevations %.1f..%.1f deg, %.0f %% of taps in "
      "view), %d features%s\n",
      path, image.width(), image.height(), strip.n_azimuth(), o.strip.elevation_min_deg,
      o.strip.elevation_max_deg, 100 * strip.visible_fraction(), count,
      surf->dropped() > 0 ? " (the strongest kept)" : "");
  for (const dsp::Surf1dFeature& f : view->features)
    std::printf("  x %4d  lobe %2d  %s blob  response %+8.2f\n", f.position, f.lobe,
                f.laplacian_sign > 0 ? "dark  " : "bright", static_cast<double>(f.response));
  return Status::Ok();
}

std::string PlotSvg(const View& a, const View& b, const dsp::LandmarkMatcher& matcher, int n) {
  constexpr double kWidth = 900, kLeft = 60, kPlotW = 820, kPanelH = 140, kTopA = 40, kTopB = 260;
  const auto x_of = [&](double column) { return kLeft + kPlotW * column / n; };
  std::string svg;
  char buf[512];
  std::snprintf(buf, sizeof buf,
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"%.0f\" height=\"440\" "
                "font-family=\"sans-serif\" font-size=\"12\">\n<rect width=\"100%%\" "
                "height=\"100%%\" fill=\"white\"/>\n",
                kWidth);
  svg += buf;
  const auto panel = [&](const View& v, double top, const char* label) {
    float lo = v.strip.empty() ? 0 : v.strip[0], hi = lo;
    for (const float s : v.strip) {
      lo = std::min(lo, s);
      hi = std::max(hi, s);
    }
    const double span = hi > lo ? static_cast<double>(hi - lo) : 1.0;
    const auto y_of = [&](float s) {
      return top + kPanelH - kPanelH * (static_cast<double>(s - lo) / span);
    };
    std::snprintf(buf, sizeof buf,
                  "<text x=\"%.0f\" y=\"%.0f\">%s: %s (%zu features)</text>\n<rect x=\"%.0f\" "
                  "y=\"%.0f\" width=\"%.0f\" height=\"%.0f\" fill=\"none\" stroke=\"#999\"/>\n",
                  kLeft, top - 8, label, v.path, v.features.size(), kLeft, top, kPlotW, kPanelH);
    svg += buf;
    svg += "<polyline fill=\"none\" stroke=\"black\" stroke-width=\"1\" points=\"";
    for (std::size_t j = 0; j < v.strip.size(); ++j) {
      std::snprintf(buf, sizeof buf, "%.1f,%.1f ", x_of(static_cast<double>(j)), y_of(v.strip[j]));
      svg += buf;
    }
    svg += "\"/>\n";
    for (const dsp::Surf1dFeature& f : v.features) {
      std::snprintf(buf, sizeof buf,
                    "<circle cx=\"%.1f\" cy=\"%.1f\" r=\"%.1f\" fill=\"none\" stroke=\"%s\"/>\n",
                    x_of(f.position), y_of(v.strip[static_cast<std::size_t>(f.position)]),
                    std::max(2.0, 0.5 * f.lobe * kPlotW / n),
                    f.laplacian_sign > 0 ? "#1f77b4" : "#ff7f0e");
      svg += buf;
    }
  };
  panel(a, kTopA, "A");
  panel(b, kTopB, "B");
  for (int i = 0; i < matcher.last_pair_count(); ++i) {
    const dsp::LandmarkMatcher::MatchedPair m = matcher.last_pair(i);
    std::snprintf(buf, sizeof buf,
                  "<line x1=\"%.1f\" y1=\"%.0f\" x2=\"%.1f\" y2=\"%.0f\" stroke=\"%s\" "
                  "stroke-width=\"%s\"/>\n",
                  x_of(m.x_stored), kTopA + kPanelH, x_of(m.x_test), kTopB,
                  m.inlier ? "#2ca02c" : "#d62728", m.inlier ? "1.2" : "0.6");
    svg += buf;
  }
  std::snprintf(buf, sizeof buf,
                "<text x=\"%.0f\" y=\"430\">azimuth 0..360 degrees left to right; circles: "
                "features (blue dark, orange bright blobs, radius ~ scale); lines: matches "
                "(green RANSAC inliers, red the rest)</text>\n</svg>\n",
                kLeft);
  svg += buf;
  return svg;
}

int CompareImages(const Options& o) {
  dsp::Surf1d surf;
  View a, b;
  for (auto [path, view] :
       {std::pair{o.images[0].c_str(), &a}, std::pair{o.images[1].c_str(), &b}}) {
    if (const Status s = Extract(o, path, &surf, view); !s.ok()) {
      return Failed("surf1d", s);
    }
  }
  const int n = static_cast<int>(a.strip.size());
  if (b.strip.size() != a.strip.size()) {
    std::fprintf(stderr, "skyloc surf1d: the strips differ in length (%zu, %zu)\n", a.strip.size(),
                 b.strip.size());
    return kExitFailure;
  }
  const dsp::LandmarkMatchOptions match_options;
  dsp::LandmarkMatcher matcher;
  dsp::LandmarkMatch m;
  dsp::Surf1dError match_error = matcher.Init(kMaxFeatures, match_options);
  if (match_error == dsp::Surf1dError::kOk)
    match_error = matcher.Match(a.features, b.features, n, &m);
  if (match_error != dsp::Surf1dError::kOk) {
    return Failed("surf1d", drivers::DspStatus(match_error, "1D SURF matching"));
  }
  std::printf("matches: %d pass the ratio test, score (sum of 1/distance) %.3f\n", m.matches,
              m.score);
  if (m.model_found) {
    std::printf("RANSAC: %d inliers, score %.3f, b_s %.4f, b_d %+.2f columns\n", m.inliers,
                m.ransac_score, m.scale, m.displacement);
    // The scene turned by +offset; the robot by -offset (dsp::LandmarkMatch).
    std::printf(
        "heading (1D SURF inliers): B's view is turned %+.2f deg from A's (the robot "
        "%+.2f deg, counter-clockwise positive)\n",
        m.heading_offset_deg, -m.heading_offset_deg);
  } else {
    std::printf("RANSAC: no line with 2 or more inliers: no heading from 1D SURF\n");
  }
  dsp::StripAlignment alignment;
  if (const dsp::StripAlignmentError e = dsp::AlignStrips(a.strip, b.strip, &alignment);
      e == dsp::StripAlignmentError::kOk) {
    std::printf(
        "heading (strip correlation): B's view is turned %+.2f deg from A's (the robot "
        "%+.2f deg), correlation %.3f, runner-up %.3f%s\n",
        alignment.heading_offset_deg, -alignment.heading_offset_deg,
        static_cast<double>(alignment.correlation), static_cast<double>(alignment.runner_up),
        alignment.runner_up > 0.9f * alignment.correlation ? " (ambiguous)" : "");
  } else {
    std::printf("heading (strip correlation): %s\n", dsp::StripAlignmentErrorMessage(e));
  }
  if (!o.plot.empty()) {
    const std::string svg = PlotSvg(a, b, matcher, n);
    std::FILE* f = std::fopen(o.plot.c_str(), "w");
    const bool written = f != nullptr && std::fwrite(svg.data(), 1, svg.size(), f) == svg.size();
    const int saved_errno = errno;
    if (f == nullptr || std::fclose(f) != 0 || !written) {
      std::fprintf(stderr, "skyloc surf1d: cannot write the plot %s: %s\n", o.plot.c_str(),
                   std::strerror(f == nullptr || !written ? saved_errno : errno));
      return kExitFailure;
    }
    std::printf("plot: %s\n", o.plot.c_str());
  }
  return kExitOk;
}

}  // namespace

int RunSurf1d(std::span<char* const> args) {
  return RunParsed(args, ParseArgs, CompareImages);
}

}  // namespace skyloc::cli
