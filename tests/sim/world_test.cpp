#include "skyloc/sim/world.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

namespace skyloc::sim {
namespace {

const std::string kSevilleCsv =
    std::string(SKYLOC_SHARED_DIR) + "/data/seville2009/world5000_triangles.csv";

TEST(World, SevilleHabitatLoads) {
  if (!std::filesystem::exists(kSevilleCsv))
    GTEST_SKIP() << kSevilleCsv << " not found (the shared data folder is not next to the repo)";
  World world;
  const Status s = LoadSevilleWorld(kSevilleCsv.c_str(), &world);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_EQ(world.triangles().size(), 5000u);
  EXPECT_EQ(world.kind, WorldKind::kSeville);
  // The README's extent: x 0..10.2, y 0..10.1, z -0.44..1.63.
  const Aabb& b = world.bvh().bounds();
  EXPECT_NEAR(b.min.z, -0.44, 0.01);
  EXPECT_NEAR(b.max.z, 1.63, 0.01);
  EXPECT_NEAR(b.max.x, 10.2, 0.1);
  EXPECT_NEAR(b.max.y, 10.1, 0.1);
  for (const Material& m : world.materials())
    EXPECT_LT(m.uv, 0.06f);  // vegetation is dark in the UV
}

class TempFile {
 public:
  explicit TempFile(const char* contents) {
    path_ =
        (std::filesystem::temp_directory_path() /
         ("skyloc_sim_test_" + std::to_string(::testing::UnitTest::GetInstance()->random_seed()) +
          "_" + ::testing::UnitTest::GetInstance()->current_test_info()->name() + ".csv"))
            .string();
    std::FILE* f = std::fopen(path_.c_str(), "w");
    std::fputs(contents, f);
    std::fclose(f);
  }
  ~TempFile() { std::filesystem::remove(path_); }
  const char* path() const { return path_.c_str(); }

 private:
  std::string path_;
};

TEST(World, SevilleLoaderNamesTheFileAndLineOfABadRow) {
  TempFile file(
      "x1,y1,z1,x2,y2,z2,x3,y3,z3,grey\n"
      "0,0,0,1,0,0,0,1,0,0.5\n"
      "0,0,0,1,0,0,0,1,oops,0.5\n");
  World world;
  const Status s = LoadSevilleWorld(file.path(), &world);
  EXPECT_EQ(s.code(), StatusCode::kInvalidArgument);
  EXPECT_NE(std::string(s.message()).find(std::string(file.path()) + ":3"), std::string::npos)
      << s.message();
}

TEST(World, SevilleLoaderRejectsGreyOutOfRangeAndMissingFiles) {
  TempFile file("0,0,0,1,0,0,0,1,0,1.5\n");
  World world;
  EXPECT_EQ(LoadSevilleWorld(file.path(), &world).code(), StatusCode::kInvalidArgument);
  EXPECT_EQ(LoadSevilleWorld("/nonexistent/world.csv", &world).code(), StatusCode::kNotFound);
}

TEST(World, ProceduralWorldsAreDeterministicAndHaveRoutes) {
  for (WorldKind kind : {WorldKind::kCity, WorldKind::kForest, WorldKind::kRepetitive}) {
    World a, b, c;
    ASSERT_TRUE(MakeProceduralWorld(kind, 11, &a).ok());
    ASSERT_TRUE(MakeProceduralWorld(kind, 11, &b).ok());
    ASSERT_TRUE(MakeProceduralWorld(kind, 12, &c).ok());
    ASSERT_EQ(a.triangles().size(), b.triangles().size());
    for (std::size_t i = 0; i < a.triangles().size(); i += 97)
      ASSERT_EQ(a.triangles()[i].a.x, b.triangles()[i].a.x);
    // Another seed is another world (positions differ even if the counts agree).
    bool differs = a.triangles().size() != c.triangles().size();
    for (std::size_t i = 0; !differs && i < a.triangles().size(); ++i)
      differs = a.triangles()[i].a.x != c.triangles()[i].a.x;
    EXPECT_TRUE(differs) << WorldKindName(kind);
    // Routes of the paper's lengths: City 520 m loop, BMX 600 m, Disposal 510 m.
    double length = 0;
    for (std::size_t i = 1; i < a.route.size(); ++i)
      length += std::hypot(a.route[i].x - a.route[i - 1].x, a.route[i].y - a.route[i - 1].y);
    if (a.route_closed)
      length +=
          std::hypot(a.route.front().x - a.route.back().x, a.route.front().y - a.route.back().y);
    EXPECT_GT(length, 480) << WorldKindName(kind);
    EXPECT_LT(length, 620) << WorldKindName(kind);
  }
}

TEST(World, ProceduralRoutesAreClearOfObstacles) {
  // A camera on the route at 1 m must not sit inside geometry: a ray straight up from
  // below every triangle's footprint would be blocked at once. Check that nothing is
  // within 0.5 m above the camera at each route vertex.
  for (WorldKind kind : {WorldKind::kCity, WorldKind::kForest, WorldKind::kRepetitive}) {
    World w;
    ASSERT_TRUE(MakeProceduralWorld(kind, 4, &w).ok());
    for (const Point2& p : w.route) {
      const Ray up{{static_cast<float>(p.x), static_cast<float>(p.y), 1.0f}, {0, 0, 1}};
      EXPECT_FALSE(w.bvh().AnyHit(up, 0, 0.5f))
          << WorldKindName(kind) << " at " << p.x << "," << p.y;
    }
  }
}

TEST(World, KindNamesRoundTrip) {
  for (const char* name : {"seville", "city", "forest", "repetitive"}) {
    WorldKind kind;
    ASSERT_TRUE(ParseWorldKind(name, &kind));
    EXPECT_STREQ(WorldKindName(kind), name);
  }
  WorldKind kind;
  EXPECT_FALSE(ParseWorldKind("moon", &kind));
}

}  // namespace
}  // namespace skyloc::sim
