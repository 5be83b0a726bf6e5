#include "skyloc/sim/bvh.h"

#include <gtest/gtest.h>

#include <vector>

#include "skyloc/sim/random.h"
#include "skyloc/sim/world.h"

namespace skyloc::sim {
namespace {

Vec3 RandomPoint(Rng& rng, float lo, float hi) {
  return {static_cast<float>(rng.Uniform(lo, hi)), static_cast<float>(rng.Uniform(lo, hi)),
          static_cast<float>(rng.Uniform(lo, hi))};
}

std::vector<Triangle> RandomTriangles(Rng& rng, int count) {
  std::vector<Triangle> triangles;
  for (int i = 0; i < count; ++i) {
    const Vec3 c = RandomPoint(rng, -10, 10);
    const float size = static_cast<float>(rng.Uniform(0.05, 2.0));
    triangles.push_back({c + RandomPoint(rng, -size, size), c + RandomPoint(rng, -size, size),
                         c + RandomPoint(rng, -size, size)});
  }
  return triangles;
}

Ray RandomRay(Rng& rng) {
  Vec3 d = RandomPoint(rng, -1, 1);
  // Some rays parallel to an axis plane, which exercise the slab test's 0 * inf case.
  if (rng.Uniform() < 0.1)
    d.z = 0;
  if (rng.Uniform() < 0.05)
    d.x = 0;
  return {RandomPoint(rng, -14, 14), d};
}

TEST(Bvh, ClosestHitEqualsBruteForceOnRandomRays) {
  Rng rng(42);
  const std::vector<Triangle> triangles = RandomTriangles(rng, 2000);
  Bvh bvh;
  ASSERT_TRUE(bvh.Build(triangles).ok());
  int hits = 0;
  for (int i = 0; i < 5000; ++i) {
    const Ray ray = RandomRay(rng);
    const float t_max = rng.Uniform() < 0.3 ? static_cast<float>(rng.Uniform(0, 20)) : kInfinity;
    const Hit expected = ClosestHitBruteForce(triangles, ray, 1e-4f, t_max);
    const Hit got = bvh.ClosestHit(ray, 1e-4f, t_max);
    ASSERT_EQ(got.triangle, expected.triangle) << "ray " << i;
    if (expected.hit()) {
      ASSERT_EQ(got.t, expected.t) << "ray " << i;
      ++hits;
    }
    ASSERT_EQ(bvh.AnyHit(ray, 1e-4f, t_max), AnyHitBruteForce(triangles, ray, 1e-4f, t_max))
        << "ray " << i;
  }
  // The test means something only if both outcomes are common.
  EXPECT_GT(hits, 500);
  EXPECT_LT(hits, 4500);
}

TEST(Bvh, MatchesBruteForceInAProceduralWorld) {
  World world;
  ASSERT_TRUE(MakeProceduralWorld(WorldKind::kCity, 3, &world).ok());
  Rng rng(7);
  const auto triangles = world.triangles();
  for (int i = 0; i < 300; ++i) {
    const Point2& p = world.route[static_cast<std::size_t>(i) % world.route.size()];
    const Ray ray{{static_cast<float>(p.x), static_cast<float>(p.y), 1.5f},
                  {static_cast<float>(rng.Uniform(-1, 1)), static_cast<float>(rng.Uniform(-1, 1)),
                   static_cast<float>(rng.Uniform(0, 1))}};
    const Hit expected = ClosestHitBruteForce(triangles, ray, 1e-4f, kInfinity);
    const Hit got = world.bvh().ClosestHit(ray, 1e-4f, kInfinity);
    ASSERT_EQ(got.triangle, expected.triangle) << "ray " << i;
    ASSERT_EQ(world.bvh().AnyHit(ray, 1e-4f, kInfinity), expected.hit());
  }
}

TEST(Bvh, CoincidentTrianglesStillBuildABoundedTree) {
  // Identical triangles defeat every split plane; the build must still terminate.
  std::vector<Triangle> same(500, Triangle{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}});
  Bvh bvh;
  ASSERT_TRUE(bvh.Build(same).ok());
  const Hit hit = bvh.ClosestHit({{0.2f, 0.2f, 1}, {0, 0, -1}}, 0, kInfinity);
  ASSERT_TRUE(hit.hit());
  EXPECT_FLOAT_EQ(hit.t, 1.0f);
}

TEST(Bvh, EmptyInputIsAnError) {
  Bvh bvh;
  EXPECT_EQ(bvh.Build({}).code(), StatusCode::kInvalidArgument);
}

}  // namespace
}  // namespace skyloc::sim
