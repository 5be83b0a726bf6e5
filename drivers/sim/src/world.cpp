#include "skyloc/sim/world.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <numbers>

#include "skyloc/sim/random.h"

namespace skyloc::sim {
namespace {

struct NamedKind {
  const char* name;
  WorldKind kind;
};
constexpr NamedKind kKinds[] = {{"seville", WorldKind::kSeville},
                                {"city", WorldKind::kCity},
                                {"forest", WorldKind::kForest},
                                {"repetitive", WorldKind::kRepetitive}};

// Octahedron subdivision on the unit sphere, then scaled. A small radial jitter keyed on
// the (shared) vertex direction makes crowns irregular without opening cracks.
void AddSphericalTriangle(World& w, Vec3 a, Vec3 b, Vec3 c, int depth, Vec3 centre, Vec3 radii,
                          std::uint32_t seed, const Material& m) {
  if (depth > 0) {
    const Vec3 ab = Normalized(a + b), bc = Normalized(b + c), ca = Normalized(c + a);
    AddSphericalTriangle(w, a, ab, ca, depth - 1, centre, radii, seed, m);
    AddSphericalTriangle(w, ab, b, bc, depth - 1, centre, radii, seed, m);
    AddSphericalTriangle(w, ca, bc, c, depth - 1, centre, radii, seed, m);
    AddSphericalTriangle(w, ab, bc, ca, depth - 1, centre, radii, seed, m);
    return;
  }
  auto place = [&](Vec3 d) {
    const float j =
        0.85f + 0.3f * HashToUnit(static_cast<std::int32_t>(std::lround(d.x * 1000)),
                                  static_cast<std::int32_t>(std::lround(d.y * 1000)),
                                  static_cast<std::int32_t>(std::lround(d.z * 1000)), seed);
    return Vec3{centre.x + d.x * radii.x * j, centre.y + d.y * radii.y * j,
                centre.z + d.z * radii.z * j};
  };
  w.AddTriangle(place(a), place(b), place(c), m);
}

}  // namespace

bool ParseWorldKind(const char* name, WorldKind* kind) {
  for (const NamedKind& k : kKinds) {
    if (std::strcmp(name, k.name) == 0) {
      *kind = k.kind;
      return true;
    }
  }
  return false;
}

const char* WorldKindName(WorldKind kind) {
  for (const NamedKind& k : kKinds) {
    if (k.kind == kind)
      return k.name;
  }
  return "?";
}

void World::AddTriangle(Vec3 a, Vec3 b, Vec3 c, const Material& m) {
  triangles_.push_back({a, b, c});
  materials_.push_back(m);
}

void World::AddQuad(Vec3 a, Vec3 b, Vec3 c, Vec3 d, const Material& m) {
  AddTriangle(a, b, c, m);
  AddTriangle(a, c, d, m);
}

void World::AddBox(double cx, double cy, double base_z, double size_x, double size_y, double height,
                   double yaw_rad, const Material& m) {
  const double c = std::cos(yaw_rad), s = std::sin(yaw_rad);
  const double hx = size_x / 2, hy = size_y / 2;
  Vec3 lo[4], hi[4];
  const double corners[4][2] = {{-hx, -hy}, {hx, -hy}, {hx, hy}, {-hx, hy}};
  for (int i = 0; i < 4; ++i) {
    const double x = cx + c * corners[i][0] - s * corners[i][1];
    const double y = cy + s * corners[i][0] + c * corners[i][1];
    lo[i] = Vec3Of(x, y, base_z);
    hi[i] = Vec3Of(x, y, base_z + height);
  }
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    AddQuad(lo[i], lo[j], hi[j], hi[i], m);
  }
  AddQuad(hi[0], hi[1], hi[2], hi[3], m);
}

void World::AddCylinder(double cx, double cy, double base_z, double radius, double height,
                        int segments, const Material& m) {
  const Vec3 top_centre = Vec3Of(cx, cy, base_z + height);
  for (int i = 0; i < segments; ++i) {
    const double a0 = 2 * std::numbers::pi * i / segments;
    const double a1 = 2 * std::numbers::pi * (i + 1) / segments;
    const Vec3 p0 = Vec3Of(cx + radius * std::cos(a0), cy + radius * std::sin(a0), base_z);
    const Vec3 p1 = Vec3Of(cx + radius * std::cos(a1), cy + radius * std::sin(a1), base_z);
    const Vec3 q0 = Vec3Of(p0.x, p0.y, base_z + height), q1 = Vec3Of(p1.x, p1.y, base_z + height);
    AddQuad(p0, p1, q1, q0, m);
    AddTriangle(q0, q1, top_centre, m);
  }
}

void World::AddEllipsoid(Vec3 centre, Vec3 radii, int subdivisions, const Material& m) {
  const Vec3 px{1, 0, 0}, nx{-1, 0, 0}, py{0, 1, 0}, ny{0, -1, 0}, pz{0, 0, 1}, nz{0, 0, -1};
  const Vec3 faces[8][3] = {{px, py, pz}, {py, nx, pz}, {nx, ny, pz}, {ny, px, pz},
                            {py, px, nz}, {nx, py, nz}, {ny, nx, nz}, {px, ny, nz}};
  const auto seed = static_cast<std::uint32_t>(std::lround(centre.x * 7 + centre.y * 13));
  for (const auto& f : faces)
    AddSphericalTriangle(*this, f[0], f[1], f[2], subdivisions, centre, radii, seed, m);
}

void World::AddBar(Vec3 from, Vec3 to, double thickness, const Material& m) {
  const Vec3 axis = to - from;
  const Vec3 helper = std::fabs(axis.z) < 0.9f * Length(axis) ? Vec3{0, 0, 1} : Vec3{1, 0, 0};
  const float h = static_cast<float>(thickness / 2);
  const Vec3 u = Normalized(Cross(axis, helper)) * h;
  const Vec3 v = Normalized(Cross(axis, u)) * h;
  const Vec3 offsets[4] = {u + v, u - v, Vec3{} - u - v, v - u};
  for (int i = 0; i < 4; ++i) {
    const int j = (i + 1) % 4;
    AddQuad(from + offsets[i], from + offsets[j], to + offsets[j], to + offsets[i], m);
  }
}

Status World::Finish() {
  SKYLOC_TRY(bvh_.Build(triangles_));
  return Status::Ok();
}

Status LoadSevilleWorld(const char* csv_path, World* world) {
  std::FILE* f = std::fopen(csv_path, "r");
  if (f == nullptr) {
    return Status::FromErrno(errno,
                             "cannot open the Seville world '%s' (it ships in "
                             "shared/data/seville2009/world5000_triangles.csv)",
                             csv_path);
  }
  *world = World{};
  world->kind = WorldKind::kSeville;
  // Bare soil between the tussocks.
  world->ground = Material{0.45f, 0.38f, 0.3f, 0.05f, Texture::kConcrete};
  char line[512];
  int line_no = 0;
  Status status;
  while (std::fgets(line, sizeof line, f) != nullptr) {
    ++line_no;
    if (line_no == 1 && std::strncmp(line, "x1,", 3) == 0)
      continue;
    if (line[0] == '\n' || line[0] == '\r' || line[0] == '\0')
      continue;
    double v[10];
    const char* p = line;
    int n = 0;
    for (; n < 10; ++n) {
      char* end = nullptr;
      v[n] = std::strtod(p, &end);
      if (end == p || !std::isfinite(v[n]))
        break;
      p = end;
      while (*p == ' ' || *p == '\t')
        ++p;
      if (n < 9) {
        if (*p != ',')
          break;
        ++p;
      }
    }
    if (n != 10) {
      status = Status::Error(StatusCode::kInvalidArgument,
                             "%s:%d: expected 10 numbers 'x1,y1,z1,x2,y2,z2,x3,y3,z3,grey', "
                             "got %d",
                             csv_path, line_no, n);
      break;
    }
    if (v[9] < 0 || v[9] > 1) {
      status = Status::Error(StatusCode::kInvalidArgument, "%s:%d: grey level %g is outside 0..1",
                             csv_path, line_no, v[9]);
      break;
    }
    const auto grey = static_cast<float>(v[9]);
    // Tussock grass: greenish in the visible, dark in the UV like all vegetation.
    const Material m{0.55f * grey, 0.75f * grey, 0.35f * grey, 0.02f + 0.03f * grey,
                     Texture::kFoliage};
    world->AddTriangle(Vec3Of(v[0], v[1], v[2]), Vec3Of(v[3], v[4], v[5]), Vec3Of(v[6], v[7], v[8]),
                       m);
  }
  std::fclose(f);
  SKYLOC_TRY(status);
  if (world->triangles().empty()) {
    return Status::Error(StatusCode::kInvalidArgument, "%s: no triangles in the file", csv_path);
  }
  return world->Finish().AddContext("%s", csv_path);
}

}  // namespace skyloc::sim
