// Simulated worlds: triangles, each with a material, plus the route the world was made
// for. Everything is triangles so that one renderer serves the real Seville ant habitat
// (loaded from CSV) and the procedural sites modelled on Stone et al. 2016 (city street
// canyon, BMX forest track, repetitive disposal-site road).
//
// World frame: x east, y north, z up, metres; the ground is the plane z = 0 (implicit:
// rays that go down without hitting a triangle hit it).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "skyloc/platform/status.h"
#include "skyloc/sim/bvh.h"
#include "skyloc/sim/geometry.h"

namespace skyloc::sim {

// Procedural surface pattern, evaluated at the hit point, so the visible image has
// appearance for an appearance-based matcher (vanilla SeqSLAM) to use.
enum class Texture : std::uint8_t { kPlain, kFoliage, kBark, kFacade, kConcrete, kGrass };

struct Material {
  float r = 0.5f, g = 0.5f, b = 0.5f;  // visible albedo, linear 0..1
  float uv = 0.05f;                    // UV (~350 nm) reflectance: low for nearly everything
  Texture texture = Texture::kPlain;
};

struct Point2 {
  double x = 0, y = 0;  // metres
};

enum class WorldKind : std::uint8_t { kSeville, kCity, kForest, kRepetitive };

// "seville", "city", "forest", "repetitive" -> kind; false for anything else.
bool ParseWorldKind(const char* name, WorldKind* kind);
const char* WorldKindName(WorldKind kind);

class World {
 public:
  // Geometry, built at start-up.
  void AddTriangle(Vec3 a, Vec3 b, Vec3 c, const Material& m);
  void AddQuad(Vec3 a, Vec3 b, Vec3 c, Vec3 d, const Material& m);  // a-b-c-d in order
  // Box standing on z = base_z, centred at (cx, cy), rotated by yaw about z; no bottom face.
  void AddBox(double cx, double cy, double base_z, double size_x, double size_y, double height,
              double yaw_rad, const Material& m);
  // Vertical cylinder (prism with `segments` sides) with a flat top.
  void AddCylinder(double cx, double cy, double base_z, double radius, double height, int segments,
                   const Material& m);
  // Closed ellipsoid (subdivided octahedron): tree crowns, bushes.
  void AddEllipsoid(Vec3 centre, Vec3 radii, int subdivisions, const Material& m);
  // A straight bar of square cross-section between two points (wires, lamp arms).
  void AddBar(Vec3 from, Vec3 to, double thickness, const Material& m);

  // Builds the BVH; call once after the geometry is complete.
  Status Finish();

  std::span<const Triangle> triangles() const { return triangles_; }
  std::span<const Material> materials() const { return materials_; }
  const Bvh& bvh() const { return bvh_; }

  // The route this world was made for (metres, ground level), empty for Seville (its
  // routes are the ant-route CSVs). `route_closed`: the last point joins the first.
  std::vector<Point2> route;
  bool route_closed = false;
  Material ground{0.35f, 0.33f, 0.3f, 0.04f, Texture::kGrass};
  WorldKind kind = WorldKind::kCity;

 private:
  std::vector<Triangle> triangles_;
  std::vector<Material> materials_;
  Bvh bvh_;
};

// The Seville 2009 ant habitat: `x1,y1,z1,x2,y2,z2,x3,y3,z3,grey` rows (header line
// optional). Errors name the file and line.
Status LoadSevilleWorld(const char* csv_path, World* world);

// A procedural world (city, forest or repetitive) from a seed, with its route.
Status MakeProceduralWorld(WorldKind kind, std::uint64_t seed, World* world);

}  // namespace skyloc::sim
