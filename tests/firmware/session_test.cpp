// RunSession as `skyloc teach` runs it: a Config in memory, a simulated camera, a route
// database in a scratch folder.
#include "firmware/session.h"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

#include "firmware/route_db.h"
#include "small_config.h"
#include "support/scratch_dir.h"

namespace skyloc::firmware {
namespace {

std::string ReadBytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream bytes;
  bytes << in.rdbuf();
  return bytes.str();
}

class SessionTeach : public ::testing::Test {
 protected:
  void SetUp() override {
    route_path_ = scratch_.path() + "/route.db";
    std::ofstream(route_path_, std::ios::binary) << kOldRoute;
    args_.mode = LoopMode::kTeach;
    args_.route_path = route_path_;
    args_.json = nullptr;
    args_.label = "teach";
    args_.simulation_expected = true;
    args_.max_frames = 3;
  }

  static constexpr const char* kOldRoute = "an earlier teach's route";
  const skyloc::testing::ScratchDir scratch_{"skyloc_session_"};
  std::string route_path_;
  SessionArgs args_;
  Config config_ = testing::SmallConfig();
};

TEST_F(SessionTeach, WithoutForceAnExistingRouteIsKeptAndTheErrorSaysForce) {
  SessionReport report;
  ::testing::internal::CaptureStderr();
  const int rc = RunSession(config_, args_, &report);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_EQ(rc, 1);
  EXPECT_EQ(report.failure, StatusCode::kAlreadyExists) << err;
  EXPECT_NE(err.find("teach: " + route_path_ +
                     " already exists: not replacing a taught route; pass --force to replace it"),
            std::string::npos)
      << err;
  EXPECT_EQ(ReadBytes(route_path_), kOldRoute);
  EXPECT_EQ(report.loop.frames, 0u);
}

TEST_F(SessionTeach, WithForceTheNewRouteReplacesTheOldOne) {
  args_.force = true;
  SessionReport report;
  ::testing::internal::CaptureStderr();
  const int rc = RunSession(config_, args_, &report);
  const std::string err = ::testing::internal::GetCapturedStderr();
  ASSERT_EQ(rc, 0) << err;
  EXPECT_EQ(report.failure, StatusCode::kOk);
  EXPECT_EQ(err.find("--force"), std::string::npos) << err;
  RouteDbLoadReport loaded;
  const Status s =
      LoadRouteDb(route_path_.c_str(), nullptr, RouteDbLoadPolicy::kStrict, nullptr, &loaded);
  ASSERT_TRUE(s.ok()) << s.message();
  EXPECT_TRUE(loaded.committed);
  EXPECT_EQ(loaded.frames, 3u);
  EXPECT_EQ(report.route_frames, 3u);
}

}  // namespace
}  // namespace skyloc::firmware
