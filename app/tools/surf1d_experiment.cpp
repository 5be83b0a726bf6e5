#include "tools/surf1d_experiment.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <span>
#include <tuple>

#include "skyloc/drivers/dsp_status.h"
#include "skyloc/drivers/image_file.h"
#include "skyloc/sim/world.h"

namespace skyloc::tools {

// The simulator's worlds and renderer, which the experiment drives.
using sim::BodyToWorld;
using sim::DefaultSimLens;
using sim::MakeProceduralWorld;
using sim::Point2;
using sim::Renderer;
using sim::Rotation;
using sim::Spectrum;
using sim::World;
using sim::WorldKind;
namespace {

// Grey value of pixel (x, y) of an RGB24 frame: the channel mean, as the sky segmenter and
// dsp::HorizonStrip read it.
double Grey(const dsp::ImageView& rgb, int x, int y) {
  const std::uint8_t* p = rgb.Row(y) + static_cast<std::size_t>(x) * 3;
  return (p[0] + p[1] + p[2]) / 3;  // integers, as HorizonStrip
}

// The features of one image, in strip columns.
struct ImageFeatures {
  std::vector<dsp::Surf1dFeature> features;
};

// Scores every pair (i < j) of `images` (i stored, j test) that `counted(i, j)` admits;
// `matches(i, j)` says whether it truly shows the same landmark.
template <typename Counted, typename Matches>
Status ScorePairs(const std::vector<ImageFeatures>& images, int n,
                  const dsp::LandmarkMatchOptions& o, Counted counted, Matches matches,
                  Surf1dCameraResult* out) {
  std::size_t capacity = 1;
  for (const ImageFeatures& f : images)
    capacity = std::max(capacity, f.features.size());
  dsp::LandmarkMatcher matcher;
  if (const dsp::Surf1dError e = matcher.Init(static_cast<int>(capacity), o);
      e != dsp::Surf1dError::kOk)
    return drivers::DspStatus(e, "landmark matcher");
  out->nn.clear();
  out->ransac.clear();
  out->matched_pairs = out->unmatched_pairs = 0;
  for (std::size_t i = 0; i < images.size(); ++i) {
    for (std::size_t j = i + 1; j < images.size(); ++j) {
      if (!counted(i, j))
        continue;
      dsp::LandmarkMatch m;
      if (const dsp::Surf1dError e = matcher.Match(images[i].features, images[j].features, n, &m);
          e != dsp::Surf1dError::kOk)
        return drivers::DspStatus(e, "landmark matcher");
      const bool match = matches(i, j);
      (match ? out->matched_pairs : out->unmatched_pairs) += 1;
      out->nn.push_back({m.score, match});
      out->ransac.push_back({m.model_found ? m.ransac_score : 0.0, match});
    }
  }
  std::vector<std::size_t> order(out->nn.size());
  for (auto [pairs, roc, auc] : {std::tuple{&out->nn, &out->roc_nn, &out->auc_nn},
                                 std::tuple{&out->ransac, &out->roc_ransac, &out->auc_ransac}}) {
    roc->resize(pairs->size() + 1);
    roc->resize(dsp::RocCurve(*pairs, order, *roc));
    if (roc->empty())
      return Status::Error(StatusCode::kInvalidArgument,
                           "surf1d experiment: need both matching and non-matching pairs (use "
                           "at least 2 places and enough images a place)");
    *auc = dsp::RocArea(*roc);
  }
  return Status::Ok();
}

std::vector<Point2> Places(const World& world, int places) {
  std::vector<Point2> out;
  const std::size_t n = world.route.size();
  for (int p = 0; p < places; ++p)
    out.push_back(world.route[(static_cast<std::size_t>(p) * 2 + 1) * n /
                              (static_cast<std::size_t>(places) * 2)]);
  return out;
}

}  // namespace

bool PinholeHorizonRow(const dsp::Lens& lens, const drivers::Pose& pose, double x, double* row) {
  // Along a column of a pinhole image the unnormalised ray (X/Z, Y/Z, 1) is linear in the
  // row, so its world height is too: take it at two rows and solve for zero.
  const double y0 = lens.centre_y();
  Eigen::Vector3d a, b;
  if (!lens.PixelToCameraRay(x, y0, &a) || !lens.PixelToCameraRay(x, y0 + 1.0, &b))
    return false;
  a /= a(2);
  b /= b(2);
  const Rotation to_world = BodyToWorld(pose);
  auto height = [&](const Eigen::Vector3d& camera) {
    const Eigen::Vector3d body = lens.camera_to_body() * camera;
    return static_cast<double>(to_world.m[2][0]) * body(0) +
           static_cast<double>(to_world.m[2][1]) * body(1) +
           static_cast<double>(to_world.m[2][2]) * body(2);
  };
  const double h0 = height(a), slope = height(b) - h0;
  if (!(std::fabs(slope) > 1e-12))
    return false;
  *row = y0 - h0 / slope;
  return *row >= -0.5 && *row <= lens.params().height - 0.5;
}

namespace {

// The shots of the experiment: `images_per_place` headings, evenly apart, at each place.
struct Shots {
  const Surf1dExperimentOptions& o;
  std::vector<Point2> places;
  std::size_t per_place() const { return static_cast<std::size_t>(o.images_per_place); }
  std::size_t total() const { return per_place() * places.size(); }
  drivers::Pose PoseOf(std::size_t k) const {
    drivers::Pose p;
    const Point2& at = places[k / per_place()];
    p.x_m = at.x;
    p.y_m = at.y;
    p.z_m = o.camera_height_m;
    p.yaw_deg = 360.0 * static_cast<double>(k % per_place()) / o.images_per_place;
    return p;
  }
  double HeadingGapDeg(std::size_t i, std::size_t j) const {
    const double d = std::fabs(PoseOf(i).yaw_deg - PoseOf(j).yaw_deg);
    return std::min(d, 360.0 - d);
  }
  bool SamePlace(std::size_t i, std::size_t j) const { return i / per_place() == j / per_place(); }
};

// The forward pinhole camera: a strip along the horizon row of each shot, its features,
// each pair of a place scored, and again without the partly overlapping non-matches.
Status RunForward(const World& world, const Shots& shots, ProgressFn progress,
                  Surf1dCameraResult* forward) {
  const Surf1dExperimentOptions& o = shots.o;
  const std::size_t total = shots.total();
  auto same_place = [&](std::size_t i, std::size_t j) { return shots.SamePlace(i, j); };
  dsp::LensParams pinhole;
  pinhole.model = dsp::LensModel::kPinhole;
  pinhole.width = o.width;
  pinhole.height = o.height;
  pinhole.fov_deg = o.fov_deg;
  pinhole.roll_deg = -90.0;  // camera x (image right) = body -y, camera z = body +x: forward
  pinhole.yaw_deg = -90.0;
  Renderer renderer;
  SKYLOC_TRY(renderer.Init(&world, pinhole));
  const int columns = o.width / o.column_step;
  const int pad = columns;  // each side: the strip sits in a periodic one 3x as long
  const int n = columns + 2 * pad;
  dsp::Surf1d surf;
  if (const dsp::Surf1dError e = surf.Init(n, o.surf); e != dsp::Surf1dError::kOk)
    return drivers::DspStatus(e, "1D SURF (forward strip)");
  SKYLOC_TRY_ASSIGN(drivers::OwnedImage frame,
                    drivers::OwnedImage::Allocate(o.width, o.height, dsp::PixelFormat::kRgb24));
  const dsp::MutableImageView view = frame.mutable_view();
  std::mt19937_64 jitter(o.world_seed * 7919u + 13u);
  std::uniform_real_distribution<double> uniform(-o.attitude_jitter_deg, o.attitude_jitter_deg);
  std::vector<float> strip(static_cast<std::size_t>(n));
  std::vector<dsp::Surf1dFeature> found(4096);
  std::vector<ImageFeatures> images(total);
  double features = 0;
  for (std::size_t k = 0; k < total; ++k) {
    if (progress != nullptr && k % shots.per_place() == 0)
      progress("forward camera: rendering and extracting");
    drivers::Pose pose = shots.PoseOf(k);
    pose.pitch_deg = o.pitch_deg + uniform(jitter);
    pose.roll_deg = uniform(jitter);
    SKYLOC_TRY(renderer.Render(pose, o.lighting, Spectrum::kVisible, k + 1, view));
    for (int s = 0; s < columns; ++s) {
      const double x = s * o.column_step + (o.column_step - 1) / 2.0;
      double horizon = 0;
      if (!PinholeHorizonRow(renderer.lens(), pose, x, &horizon))
        return Status::Error(StatusCode::kInvalidArgument,
                             "surf1d experiment: the horizon is outside the forward image at "
                             "pitch %.1f degrees: use a smaller --pitch",
                             pose.pitch_deg);
      const int column = std::clamp(static_cast<int>(std::lround(x)), 0, o.width - 1);
      const int top = static_cast<int>(std::lround(horizon)) - o.band_rows / 2;
      double sum = 0;
      int taps = 0;
      for (int r = std::max(top, 0); r < std::min(top + o.band_rows, o.height); ++r, ++taps)
        sum += Grey(view, column, r);
      strip[static_cast<std::size_t>(pad + s)] = static_cast<float>(sum / std::max(taps, 1));
    }
    // The padding: a ramp from the last column back round to the first.
    const float first = strip[static_cast<std::size_t>(pad)];
    const float last = strip[static_cast<std::size_t>(pad + columns - 1)];
    for (int i = 1; i <= 2 * pad; ++i) {
      const float t = static_cast<float>(i) / static_cast<float>(2 * pad + 1);
      strip[static_cast<std::size_t>((pad + columns - 1 + i) % n)] = last + (first - last) * t;
    }
    int count = 0;
    if (const dsp::Surf1dError e = surf.Detect(strip, found, &count); e != dsp::Surf1dError::kOk)
      return drivers::DspStatus(e, "1D SURF (forward strip)");
    for (int f = 0; f < count; ++f) {
      const int x = found[static_cast<std::size_t>(f)].position;
      if (x >= pad && x < pad + columns)
        images[k].features.push_back(found[static_cast<std::size_t>(f)]);
    }
    features += static_cast<double>(images[k].features.size());
  }
  char camera[96];
  std::snprintf(camera, sizeof camera, "forward pinhole %dx%d, %.3g deg", o.width, o.height,
                o.fov_deg);
  forward->camera = camera;
  forward->strip_columns = columns;
  forward->mean_features = features / static_cast<double>(total);
  if (progress != nullptr)
    progress("forward camera: matching pairs");
  SKYLOC_TRY(ScorePairs(
      images, n, o.match, same_place,
      [&](std::size_t i, std::size_t j) { return shots.HeadingGapDeg(i, j) < o.match_below_deg; },
      forward));

  // The same scores without the partly overlapping non-matches.
  std::vector<dsp::ScoredPair> nn, ransac;
  std::size_t pair = 0;
  for (std::size_t i = 0; i < total; ++i) {
    for (std::size_t j = i + 1; j < total; ++j) {
      if (!shots.SamePlace(i, j))
        continue;
      const double gap = shots.HeadingGapDeg(i, j);
      if (gap < o.match_below_deg || gap >= o.fov_deg) {
        nn.push_back(forward->nn[pair]);
        ransac.push_back(forward->ransac[pair]);
      }
      forward->disjoint_pairs += gap >= o.fov_deg ? 1 : 0;
      ++pair;
    }
  }
  std::vector<std::size_t> order(nn.size());
  std::vector<dsp::RocPoint> roc(nn.size() + 1);
  forward->auc_nn_disjoint = dsp::RocArea(std::span(roc).first(dsp::RocCurve(nn, order, roc)));
  forward->auc_ransac_disjoint =
      dsp::RocArea(std::span(roc).first(dsp::RocCurve(ransac, order, roc)));

  return Status::Ok();
}

// The upward fisheye: its 360-degree strip of each shot, its features, each pair of a place
// scored (every pair of a place sees the same sky, turned).
Status RunUpward(const World& world, const Shots& shots, ProgressFn progress,
                 Surf1dCameraResult* fisheye) {
  const Surf1dExperimentOptions& o = shots.o;
  const std::size_t total = shots.total();
  auto same_place = [&](std::size_t i, std::size_t j) { return shots.SamePlace(i, j); };
  std::vector<dsp::Surf1dFeature> found(4096);
  std::vector<ImageFeatures> images(total);
  double features = 0;
  Renderer up;
  SKYLOC_TRY(up.Init(&world, DefaultSimLens(o.fisheye_width, o.fisheye_height)));
  dsp::HorizonStrip horizon;
  if (const dsp::HorizonStripError e = horizon.Init(up.lens(), o.fisheye_strip);
      e != dsp::HorizonStripError::kOk)
    return Status::Error(StatusCode::kInvalidArgument, "horizon strip: %s",
                         dsp::HorizonStripErrorMessage(e));
  const int m = horizon.n_azimuth();
  dsp::Surf1d surf_up;
  if (const dsp::Surf1dError e = surf_up.Init(m, o.surf); e != dsp::Surf1dError::kOk)
    return drivers::DspStatus(e, "1D SURF (fisheye strip)");
  SKYLOC_TRY_ASSIGN(
      drivers::OwnedImage frame_up,
      drivers::OwnedImage::Allocate(o.fisheye_width, o.fisheye_height, dsp::PixelFormat::kRgb24));
  const dsp::MutableImageView view_up = frame_up.mutable_view();
  std::vector<float> strip_up(static_cast<std::size_t>(m));
  for (std::size_t k = 0; k < total; ++k) {
    if (progress != nullptr && k % shots.per_place() == 0)
      progress("upward fisheye: rendering and extracting");
    SKYLOC_TRY(up.Render(shots.PoseOf(k), o.lighting, Spectrum::kVisible, k + 1, view_up));
    if (const dsp::HorizonStripError e = horizon.Extract(view_up, strip_up);
        e != dsp::HorizonStripError::kOk)
      return Status::Error(StatusCode::kInvalidArgument, "horizon strip: %s",
                           dsp::HorizonStripErrorMessage(e));
    int count = 0;
    if (const dsp::Surf1dError e = surf_up.Detect(strip_up, found, &count);
        e != dsp::Surf1dError::kOk)
      return drivers::DspStatus(e, "1D SURF (fisheye strip)");
    images[k].features.assign(found.begin(), found.begin() + count);
    features += count;
  }
  fisheye->camera = std::string("upward fisheye ") + std::to_string(o.fisheye_width) + "x" +
                    std::to_string(o.fisheye_height) + ", 360-degree strip";
  fisheye->strip_columns = m;
  fisheye->mean_features = features / static_cast<double>(total);
  if (progress != nullptr)
    progress("upward fisheye: matching pairs");
  return ScorePairs(
      images, m, o.match, [](std::size_t, std::size_t) { return true; }, same_place, fisheye);
}

}  // namespace

Status RunSurf1dExperiment(const Surf1dExperimentOptions& options, Surf1dCameraResult* forward,
                           Surf1dCameraResult* fisheye, ProgressFn progress) {
  const Surf1dExperimentOptions& o = options;
  if (o.images_per_place < 4 || o.places < 1 || o.column_step < 1 || o.band_rows < 1)
    return Status::Error(StatusCode::kInvalidArgument,
                         "surf1d experiment: need at least 4 images a place, 1 place, a column "
                         "step and band rows of at least 1");
  if (progress != nullptr)
    progress("city world");
  World world;
  SKYLOC_TRY(MakeProceduralWorld(WorldKind::kCity, o.world_seed, &world));
  const Shots shots{o, Places(world, o.places)};
  SKYLOC_TRY(RunForward(world, shots, progress, forward));
  return RunUpward(world, shots, progress, fisheye);
}

}  // namespace skyloc::tools
