// Procedural worlds modelled on the three sites of Stone et al. 2016 (section IV-B), built
// from a seed so the demo and tests run without the shared data folder. Objects are placed
// relative to the route: at arc length s along it, offset sideways (left positive).
//
// Every random draw is a statement of its own, in a fixed order: the arguments of one call
// are evaluated in an unspecified order, and GCC draws them right to left on x86-64 and
// left to right on ARM, which built different worlds from one seed (heights, sizes and
// materials swapped). The order written here is the one x86-64 drew, so its worlds (and
// every result measured on them) stay as they were.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "skyloc/dsp/angles.h"
#include "skyloc/sim/random.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {
namespace {

// Arc-length access to a polyline.
class Polyline {
 public:
  explicit Polyline(const std::vector<Point2>& points, bool closed) : points_(points) {
    if (closed && !points_.empty())
      points_.push_back(points_.front());
    cumulative_.push_back(0);
    for (std::size_t i = 1; i < points_.size(); ++i) {
      cumulative_.push_back(cumulative_.back() + std::hypot(points_[i].x - points_[i - 1].x,
                                                            points_[i].y - points_[i - 1].y));
    }
  }
  double length() const { return cumulative_.back(); }
  // Position and unit tangent at arc length s (clamped to the ends).
  void At(double s, double* x, double* y, double* tx, double* ty) const {
    s = std::clamp(s, 0.0, length());
    std::size_t i = 1;
    while (i + 1 < points_.size() && cumulative_[i] < s)
      ++i;
    const double seg = cumulative_[i] - cumulative_[i - 1];
    const double f = seg > 0 ? (s - cumulative_[i - 1]) / seg : 0;
    const Point2& a = points_[i - 1];
    const Point2& b = points_[i];
    *x = a.x + f * (b.x - a.x);
    *y = a.y + f * (b.y - a.y);
    *tx = seg > 0 ? (b.x - a.x) / seg : 1;
    *ty = seg > 0 ? (b.y - a.y) / seg : 0;
  }
  // A point `offset` metres to the left of the route at s; heading of the route there.
  Point2 Side(double s, double offset, double* heading) const {
    double x, y, tx, ty;
    At(s, &x, &y, &tx, &ty);
    if (heading != nullptr)
      *heading = std::atan2(ty, tx);
    return {x - ty * offset, y + tx * offset};
  }
  // Distance from p to the polyline (brute force: worlds are built once).
  double DistanceTo(Point2 p) const {
    double best = 1e30;
    for (std::size_t i = 1; i < points_.size(); ++i) {
      const Point2& a = points_[i - 1];
      const Point2& b = points_[i];
      const double dx = b.x - a.x, dy = b.y - a.y;
      const double len2 = dx * dx + dy * dy;
      const double t =
          len2 > 0 ? std::clamp(((p.x - a.x) * dx + (p.y - a.y) * dy) / len2, 0.0, 1.0) : 0.0;
      best = std::min(best, std::hypot(p.x - (a.x + t * dx), p.y - (a.y + t * dy)));
    }
    return best;
  }

 private:
  std::vector<Point2> points_;
  std::vector<double> cumulative_;
};

Material Mat(double r, double g, double b, double uv, Texture t) {
  return {static_cast<float>(r), static_cast<float>(g), static_cast<float>(b),
          static_cast<float>(uv), t};
}

const Material kBark = Mat(0.28, 0.2, 0.14, 0.03, Texture::kBark);
const Material kMetal = Mat(0.45, 0.46, 0.48, 0.08, Texture::kPlain);
const Material kWire = Mat(0.05, 0.05, 0.05, 0.02, Texture::kPlain);
const Material kRoof = Mat(0.45, 0.18, 0.12, 0.04, Texture::kConcrete);

Material Foliage(Rng& rng) {
  const double k = rng.Uniform(0.8, 1.2);
  return Mat(0.12 * k, 0.32 * k, 0.08 * k, 0.025, Texture::kFoliage);
}

Material Facade(Rng& rng) {
  static constexpr double kColours[][3] = {
      {0.75, 0.7, 0.6}, {0.6, 0.6, 0.62}, {0.55, 0.3, 0.22}, {0.8, 0.78, 0.72}, {0.5, 0.45, 0.4}};
  const auto i = static_cast<std::size_t>(rng.Next() % 5);
  return Mat(kColours[i][0], kColours[i][1], kColours[i][2], 0.06, Texture::kFacade);
}

void AddTree(World& w, double x, double y, double trunk_radius, double crown_base, Vec3 crown_radii,
             const Material& foliage) {
  const double crown_half_height = crown_radii.z;
  w.AddCylinder(x, y, 0, trunk_radius, crown_base + crown_half_height * 0.5, 6, kBark);
  w.AddEllipsoid(Vec3Of(x, y, crown_base + crown_half_height), crown_radii, 1, foliage);
}

// House with a pitched roof, ridge along its local x axis.
void AddHouse(World& w, double cx, double cy, double size_x, double size_y, double wall_h,
              double roof_h, double yaw, const Material& facade) {
  w.AddBox(cx, cy, 0, size_x, size_y, wall_h, yaw, facade);
  const double c = std::cos(yaw), s = std::sin(yaw);
  auto at = [&](double lx, double ly, double z) {
    return Vec3Of(cx + c * lx - s * ly, cy + s * lx + c * ly, z);
  };
  const double hx = size_x / 2 + 0.3, hy = size_y / 2 + 0.3;
  const Vec3 r0 = at(-hx, 0, wall_h + roof_h), r1 = at(hx, 0, wall_h + roof_h);
  w.AddQuad(at(-hx, -hy, wall_h), at(hx, -hy, wall_h), r1, r0, kRoof);
  w.AddQuad(at(-hx, hy, wall_h), at(hx, hy, wall_h), r1, r0, kRoof);
  w.AddTriangle(at(-hx, -hy, wall_h), at(-hx, hy, wall_h), r0, facade);
  w.AddTriangle(at(hx, -hy, wall_h), at(hx, hy, wall_h), r1, facade);
}

// A house of random facade and size at (x, y), ridge along yaw. The draws are separate
// statements in one fixed order (facade, roof, wall, depth, width): the order of a call's
// arguments is unspecified, and GCC evaluates them in opposite orders on x86-64 and ARM.
void AddRandomHouse(World& w, Rng& rng, Point2 at, double yaw, double wall_lo, double wall_hi,
                    double width_lo, double width_hi) {
  const Material facade = Facade(rng);
  const double roof_h = rng.Uniform(2.5, 4);
  const double wall_h = rng.Uniform(wall_lo, wall_hi);
  const double size_y = rng.Uniform(7, 9);
  const double size_x = rng.Uniform(width_lo, width_hi);
  AddHouse(w, at.x, at.y, size_x, size_y, wall_h, roof_h, yaw, facade);
}

void AddLampPost(World& w, const Polyline& route, double s, double offset) {
  double heading;
  const Point2 base = route.Side(s, offset, &heading);
  const Point2 arm = route.Side(s, offset + (offset > 0 ? -1.8 : 1.8), nullptr);
  w.AddCylinder(base.x, base.y, 0, 0.09, 7.0, 6, kMetal);
  w.AddBar(Vec3Of(base.x, base.y, 6.9), Vec3Of(arm.x, arm.y, 6.9), 0.08, kMetal);
  w.AddBox(arm.x, arm.y, 6.7, 0.6, 0.3, 0.2, heading, kMetal);
}

// City: a ~520 m loop of street canyons (the paper's Bielefeld City circuit).
void MakeCity(World& w, Rng& rng) {
  w.ground = Mat(0.22, 0.22, 0.23, 0.03, Texture::kConcrete);
  // A rectangle with chamfered corners: 160 m x 100 m, 10 m chamfers -> ~503 m.
  const double a = 80, b = 50, k = 10;
  w.route = {{-a + k, -b}, {a - k, -b}, {a, -b + k}, {a, b - k},
             {a - k, b},   {-a + k, b}, {-a, b - k}, {-a, -b + k}};
  w.route_closed = true;
  const Polyline route(w.route, true);
  const double length = route.length();
  // Buildings on both sides, of varied heights and widths, with the odd gap; crossings
  // (open sky) near the corners.
  for (int side = -1; side <= 1; side += 2) {
    double s = 0;
    while (s < length) {
      const double width = rng.Uniform(8, 22);
      const double centre_s = s + width / 2;
      double heading;
      const double setback = rng.Uniform(7.5, 9.5);
      const double depth = rng.Uniform(10, 16);
      const Point2 c = route.Side(centre_s, side * (setback + depth / 2), &heading);
      // Keep street crossings clear: no building whose footprint reaches the street.
      const double clearance = route.DistanceTo(c);
      if (clearance > setback + depth / 2 - 0.5 && rng.Uniform() > 0.12) {
        const Material facade = Facade(rng);
        const double height = rng.Uniform(6, 28);
        w.AddBox(c.x, c.y, 0, width - 0.4, depth, height, heading, facade);
      }
      s += width + (rng.Uniform() < 0.15 ? rng.Uniform(3, 8) : 0);
    }
  }
  // Lamp posts every 30 m on the right, overhead (tram) wires across and along the street.
  Point2 previous{};
  bool have_previous = false;
  for (double s = 5; s < length; s += 30) {
    AddLampPost(w, route, s, -6.0);
    AddLampPost(w, route, s, 6.0);
    const Point2 l = route.Side(s, 6.0, nullptr), r = route.Side(s, -6.0, nullptr);
    w.AddBar(Vec3Of(l.x, l.y, 7.4), Vec3Of(r.x, r.y, 7.4), 0.04, kWire);
    const Point2 mid = route.Side(s, 0, nullptr);
    if (have_previous)
      w.AddBar(Vec3Of(previous.x, previous.y, 7.4), Vec3Of(mid.x, mid.y, 7.4), 0.04, kWire);
    previous = mid;
    have_previous = true;
  }
  // A few street trees.
  for (double s = 20; s < length; s += rng.Uniform(40, 90)) {
    const Point2 p = route.Side(s, rng.Uniform() < 0.5 ? 5.0 : -5.0, nullptr);
    const double r = rng.Uniform(2, 3);
    AddTree(w, p.x, p.y, 0.2, 3, Vec3Of(r, r, r * 1.2), Foliage(rng));
  }
}

// Winding route of `length` metres in 5 m steps; `wiggle` is the heading random walk step.
std::vector<Point2> WindingRoute(Rng& rng, double length, double wiggle_rad_first,
                                 double wiggle_rad_rest, double switch_s) {
  std::vector<Point2> route{{0, 0}};
  double heading = 0, turn = 0;
  for (double s = 5; s <= length + 1e-9; s += 5) {
    const double wiggle = s < switch_s ? wiggle_rad_first : wiggle_rad_rest;
    turn = std::clamp(0.7 * turn + rng.Uniform(-wiggle, wiggle), -2 * wiggle, 2 * wiggle);
    heading += turn;
    const Point2& p = route.back();
    route.push_back({p.x + 5 * std::cos(heading), p.y + 5 * std::sin(heading)});
  }
  return route;
}

// Forest (BMX track): dense canopy with gaps, then a forest edge with gardens on the left,
// then a suburban street. ~600 m.
void MakeForest(World& w, Rng& rng) {
  w.ground = Mat(0.3, 0.26, 0.18, 0.03, Texture::kGrass);
  w.route = WindingRoute(rng, 600, 0.12, 0.03, 250);
  w.route_closed = false;
  const Polyline route(w.route, false);
  // Trees scattered in a corridor; density and side depend on the section.
  for (double s = -30; s < 480; s += 1.0) {
    for (int k = 0; k < 6; ++k) {
      const double offset = rng.Uniform(-40, 40);
      const bool forest = s < 250;
      const bool edge = s >= 250 && s < 450;
      double p = 0;
      if (forest)
        p = 0.4;
      else if (edge && offset < -3)
        p = 0.25;  // forest on the right
      if (rng.Uniform() >= p || std::fabs(offset) < 2.5)
        continue;
      // Clearings: canopy gaps every so often along the track.
      const double phase = std::fmod(s + 1000, 70.0);
      if (forest && phase > 50 && phase < 58 && std::fabs(offset) < 12)
        continue;
      const Point2 c = route.Side(s, offset, nullptr);
      if (route.DistanceTo(c) < 2.5)
        continue;
      const double r = rng.Uniform(2.5, 4.5);
      const Material foliage = Foliage(rng);
      const double crown_half_height = rng.Uniform(3, 5.5);
      const double crown_aspect = rng.Uniform(0.8, 1.2);
      const double crown_base = rng.Uniform(3, 7);
      const double trunk_radius = rng.Uniform(0.15, 0.35);
      AddTree(w, c.x, c.y, trunk_radius, crown_base, Vec3Of(r, r * crown_aspect, crown_half_height),
              foliage);
    }
  }
  // Gardens on the left of the forest edge: hedges, houses, small trees.
  for (double s = 255; s < 450; s += rng.Uniform(18, 26)) {
    double heading;
    const Point2 hedge = route.Side(s, 4.5, &heading);
    const Material hedge_foliage = Foliage(rng);
    const double hedge_height = rng.Uniform(1.2, 2.0);
    w.AddBox(hedge.x, hedge.y, 0, 16, 0.8, hedge_height, heading, hedge_foliage);
    const Point2 house = route.Side(s, rng.Uniform(15, 19), nullptr);
    AddRandomHouse(w, rng, house, heading, 5, 6.5, 8, 11);
    if (rng.Uniform() < 0.6) {
      const Point2 t = route.Side(s + 9, rng.Uniform(7, 10), nullptr);
      const double r = rng.Uniform(1.5, 2.5);
      AddTree(w, t.x, t.y, 0.15, 2, Vec3Of(r, r, r), Foliage(rng));
    }
  }
  // Suburban street: houses both sides, street trees, lamp posts.
  for (int side = -1; side <= 1; side += 2) {
    for (double s = 450; s < route.length() + 20; s += rng.Uniform(16, 24)) {
      double heading;
      const Point2 house = route.Side(s, side * rng.Uniform(11, 14), &heading);
      AddRandomHouse(w, rng, house, heading, 5, 7, 9, 12);
      if (rng.Uniform() < 0.5) {
        const Point2 t = route.Side(s + 8, side * 5.0, nullptr);
        const double r = rng.Uniform(1.8, 3);
        AddTree(w, t.x, t.y, 0.18, 2.5, Vec3Of(r, r, r * 1.1), Foliage(rng));
      }
    }
  }
  for (double s = 460; s < route.length(); s += 35)
    AddLampPost(w, route, s, -5.5);
}

// Repetitive (disposal site): a ~510 m forest road lined with near-identical trees in
// regular rows, one junction, one building and an open disposal area. Aliasing on purpose.
void MakeRepetitive(World& w, Rng& rng) {
  w.ground = Mat(0.3, 0.28, 0.22, 0.03, Texture::kGrass);
  w.route = {{0, 0}, {180, 0}, {300, 25}, {510, 25}};
  w.route_closed = false;
  const Polyline route(w.route, false);
  const double junction_s = 330;  // side road to the left
  const double disposal_s = 400;  // clearing on the right, with the building
  const Material foliage = Mat(0.12, 0.3, 0.09, 0.025, Texture::kFoliage);
  auto tree = [&](Point2 p) {
    const double j = rng.Uniform(0.97, 1.03);  // near-identical on purpose
    const double dy = rng.Uniform(-0.3, 0.3);
    const double dx = rng.Uniform(-0.3, 0.3);
    AddTree(w, p.x + dx, p.y + dy, 0.25, 4.5 * j, Vec3Of(3.0 * j, 3.0 * j, 4.0 * j), foliage);
  };
  for (double s = -20; s < route.length() + 20; s += 7) {
    for (double offset : {5.5, 12.5, 19.5, -5.5, -12.5, -19.5}) {
      if (offset > 0 && std::fabs(s - junction_s) < 7)
        continue;
      if (offset < 0 && s > disposal_s - 20 && s < disposal_s + 45)
        continue;
      const Point2 p = route.Side(s, offset, nullptr);
      if (route.DistanceTo(p) < 4.5)
        continue;
      tree(p);
    }
  }
  // Trees along the side road (going left from the junction).
  double heading;
  route.Side(junction_s, 0, &heading);
  const double sx = std::cos(heading + dsp::kPi / 2), sy = std::sin(heading + dsp::kPi / 2);
  const double fx = std::cos(heading), fy = std::sin(heading);
  const Point2 j = route.Side(junction_s, 0, nullptr);
  for (double d = 12; d < 80; d += 7) {
    for (double side : {-5.5, 5.5}) {
      tree({j.x + sx * d + fx * side, j.y + sy * d + fy * side});
    }
  }
  // The disposal site: low piles and one small building.
  for (int i = 0; i < 6; ++i) {
    const double offset = -rng.Uniform(9, 25);
    const Point2 p = route.Side(disposal_s + rng.Uniform(-10, 35), offset, nullptr);
    const double yaw = rng.Uniform(0, dsp::kPi);
    const double height = rng.Uniform(1.5, 3);
    const double size_y = rng.Uniform(3, 6);
    const double size_x = rng.Uniform(3, 6);
    w.AddBox(p.x, p.y, 0, size_x, size_y, height, yaw,
             Mat(0.4, 0.36, 0.3, 0.04, Texture::kConcrete));
  }
  const Point2 b = route.Side(disposal_s + 20, -12, &heading);
  AddHouse(w, b.x, b.y, 10, 7, 4, 1.5, heading, Mat(0.7, 0.68, 0.62, 0.06, Texture::kFacade));
}

}  // namespace

Status MakeProceduralWorld(WorldKind kind, std::uint64_t seed, World* world) {
  *world = World{};
  world->kind = kind;
  Rng rng(seed * 0x9E3779B97F4A7C15ull + static_cast<std::uint64_t>(kind));
  switch (kind) {
    case WorldKind::kCity:
      MakeCity(*world, rng);
      break;
    case WorldKind::kForest:
      MakeForest(*world, rng);
      break;
    case WorldKind::kRepetitive:
      MakeRepetitive(*world, rng);
      break;
    case WorldKind::kSeville:
      return Status::Error(StatusCode::kInvalidArgument,
                           "the seville world is loaded from its CSV (LoadSevilleWorld), it "
                           "has no procedural version");
  }
  return world->Finish();
}

}  // namespace skyloc::sim
