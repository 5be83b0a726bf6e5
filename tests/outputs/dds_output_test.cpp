// The DDS output ([output] kinds = "dds") seen by a subscriber on Cyclone DDS's own C API,
// as a ROS 2 node on rmw_cyclonedds_cpp would see it: `skyloc repeat` (RunSession) on a
// simulated route publishes every frame on rt/skyloc/localisation, typed
// skyloc_msgs::msg::dds_::Localisation_, with the values of the frame's JSON line; the
// health goes to rt/diagnostics as a diagnostic_msgs DiagnosticArray.
#include <gtest/gtest.h>

#if SKYLOC_WITH_DDS
#include <dds/dds.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>
#include <vector>

#include "firmware/session.h"
#include "firmware/small_config.h"
#include "ros2_types.h"
#include "skyloc/drivers/dds_output.h"
#include "support/scratch_dir.h"

namespace skyloc::firmware {
namespace {

// A subscriber of one topic: best effort (what the writer offers), keeping every sample.
struct Subscriber {
  dds_entity_t participant = 0, reader = 0;
  Subscriber(const dds_topic_descriptor_t* type, const char* topic_name, bool reliable) {
    participant = dds_create_participant(0, nullptr, nullptr);
    const dds_entity_t topic = dds_create_topic(participant, type, topic_name, nullptr, nullptr);
    dds_qos_t* qos = dds_create_qos();
    dds_qset_reliability(qos, reliable ? DDS_RELIABILITY_RELIABLE : DDS_RELIABILITY_BEST_EFFORT,
                         DDS_SECS(1));
    dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
    reader = dds_create_reader(participant, topic, qos, nullptr);
    dds_delete_qos(qos);
  }
  ~Subscriber() {
    if (participant > 0)
      dds_delete(participant);
  }
};

// The value of "key" in a JSON line: its text up to the next ',' or '}'.
std::string Field(const std::string& line, const char* key) {
  const std::string k = std::string("\"") + key + "\":";
  const std::size_t at = line.find(k);
  if (at == std::string::npos)
    return "(missing)";
  const std::size_t from = at + k.size();
  return line.substr(from, line.find_first_of(",}", from) - from);
}
double Number(const std::string& text) {
  return text == "null" ? std::numeric_limits<double>::quiet_NaN()
                        : std::strtod(text.c_str(), nullptr);
}

// A number printed with `decimals` digits equals the sample's value to within half a digit.
void ExpectPrinted(const std::string& json, double value, int decimals, const char* what,
                   std::uint64_t frame) {
  if (json == "null") {
    EXPECT_TRUE(std::isnan(value)) << what << " of frame " << frame << ": " << value;
    return;
  }
  EXPECT_NEAR(Number(json), value, 0.5 * std::pow(10.0, -decimals) + 1e-9)
      << what << " of frame " << frame;
}

TEST(DdsOutput, TheTypeIsNamedAsRos2NamesIt) {
  EXPECT_STREQ(skyloc_msgs_msg_dds__Localisation__desc.m_typename,
               "skyloc_msgs::msg::dds_::Localisation_");
  EXPECT_STREQ(diagnostic_msgs_msg_dds__DiagnosticArray__desc.m_typename,
               "diagnostic_msgs::msg::dds_::DiagnosticArray_");
}

TEST(DdsOutput, ASubscriberSeesEveryFrameOfRepeatAsItsJsonLine) {
  const skyloc::testing::ScratchDir dir("skyloc-dds-");
  Config config = testing::SmallConfig();
  config.camera.sim.name = "city";
  SessionArgs teach;
  teach.mode = LoopMode::kTeach;
  teach.route_path = dir.path() + "/route.db";
  teach.json = nullptr;
  teach.simulation_expected = true;
  teach.max_frames = 150;
  teach.label = "teach";
  ::testing::internal::CaptureStderr();
  ASSERT_EQ(RunSession(config, teach), 0) << ::testing::internal::GetCapturedStderr();
  ::testing::internal::GetCapturedStderr();

  Subscriber subscriber(&skyloc_msgs_msg_dds__Localisation__desc, "rt/skyloc/localisation", false);
  ASSERT_GT(subscriber.reader, 0) << dds_strretcode(subscriber.reader);
  config.output.to_dds = true;
  SessionArgs repeat = teach;
  repeat.mode = LoopMode::kRepeat;
  repeat.label = "repeat";
  const std::string lines_path = dir.path() + "/stdout.jsonl";
  repeat.json = std::fopen(lines_path.c_str(), "w");
  ASSERT_NE(repeat.json, nullptr);
  ::testing::internal::CaptureStderr();
  const int rc = RunSession(config, repeat);
  const std::string err = ::testing::internal::GetCapturedStderr();
  std::fclose(repeat.json);
  ASSERT_EQ(rc, 0) << err;
  EXPECT_NE(err.find("output dds: ROS 2 topic /skyloc/localisation"), std::string::npos) << err;

  // The frames' lines; the devices' record lines between them are not on this topic.
  std::vector<std::string> lines;
  std::ifstream in(lines_path);
  for (std::string line; std::getline(in, line);)
    if (line.rfind("{\"devices\":", 0) != 0)
      lines.push_back(line);
  ASSERT_EQ(lines.size(), 150u);

  // Loaned samples: Cyclone owns their memory until dds_return_loan.
  std::vector<void*> loans(200, nullptr);
  std::vector<dds_sample_info_t> infos(loans.size());
  const dds_return_t taken = dds_take(subscriber.reader, loans.data(), infos.data(), loans.size(),
                                      static_cast<uint32_t>(loans.size()));
  ASSERT_EQ(taken, 150) << "the subscriber did not see every frame";
  const char* states[] = {"\"LOST\"", "\"SEARCHING\"", "\"LOCALISED\""};
  std::size_t localised = 0, with_distance = 0;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto& s = *static_cast<const skyloc_msgs_msg_dds__Localisation_*>(loans[i]);
    const std::string& line = lines[i];
    ASSERT_TRUE(infos[i].valid_data);
    EXPECT_EQ(Field(line, "frame"), std::to_string(s.frame)) << line;
    const double stamp = s.header.stamp.sec + s.header.stamp.nanosec * 1e-9;
    ExpectPrinted(Field(line, "timestamp"), stamp, 6, "timestamp", s.frame);
    EXPECT_STREQ(s.header.frame_id, "skyloc");
    ASSERT_LT(s.state, 3);
    EXPECT_EQ(Field(line, "state"), states[s.state]) << line;
    EXPECT_EQ(Field(line, "best_index"),
              s.route_index < 0 ? std::string("null") : std::to_string(s.route_index));
    EXPECT_EQ(Field(line, "route_length"), std::to_string(s.route_length));
    EXPECT_EQ(s.route_length, 150u);
    ExpectPrinted(Field(line, "distance_m"), s.distance_along_route_m, 2, "distance", s.frame);
    ExpectPrinted(Field(line, "confidence"), s.confidence, 4, "confidence", s.frame);
    ExpectPrinted(Field(line, "uniqueness"), s.uniqueness, 4, "uniqueness", s.frame);
    ExpectPrinted(Field(line, "heading_deg"), s.heading_deg, 2, "heading", s.frame);
    ExpectPrinted(Field(line, "heading_confidence"), s.heading_confidence, 4, "heading confidence",
                  s.frame);
    EXPECT_EQ(Field(line, "latency_us"), std::to_string(s.latency_us));
    localised += s.state == 2 ? 1u : 0u;
    with_distance += std::isfinite(s.distance_along_route_m) ? 1u : 0u;
  }
  // A real run: it localised, and the simulated route's poses gave distances.
  EXPECT_GT(localised, 50u);
  EXPECT_GT(with_distance, 50u);
  dds_return_loan(subscriber.reader, loans.data(), taken);
}

TEST(DdsOutput, HealthGoesToDiagnosticsAsKeyValues) {
  Subscriber subscriber(&diagnostic_msgs_msg_dds__DiagnosticArray__desc, "rt/diagnostics", true);
  ASSERT_GT(subscriber.reader, 0);
  drivers::DdsOutput output({});
  ASSERT_TRUE(output.Open().ok());
  output.PublishHealth("frames=12\nstate=LOCALISED\n");
  void* sample = nullptr;
  dds_sample_info_t info;
  const dds_return_t taken = dds_take(subscriber.reader, &sample, &info, 1, 1);
  ASSERT_EQ(taken, 1);
  const auto* array = static_cast<const diagnostic_msgs_msg_dds__DiagnosticArray_*>(sample);
  ASSERT_EQ(array->status._length, 1u);
  const diagnostic_msgs_msg_dds__DiagnosticStatus_& status = array->status._buffer[0];
  EXPECT_STREQ(status.hardware_id, "skyloc");
  ASSERT_EQ(status.values._length, 2u);
  EXPECT_STREQ(status.values._buffer[0].key, "frames");
  EXPECT_STREQ(status.values._buffer[0].value, "12");
  EXPECT_STREQ(status.values._buffer[1].key, "state");
  EXPECT_STREQ(status.values._buffer[1].value, "LOCALISED");
  dds_return_loan(subscriber.reader, &sample, taken);
  output.Close();
}

}  // namespace
}  // namespace skyloc::firmware

#else
// A build without Cyclone DDS: `dds` in the configuration is a clear error.
#include "firmware/session.h"
#include "firmware/small_config.h"

namespace skyloc::firmware {
namespace {
TEST(DdsOutput, WithoutCycloneDdsTheConfigurationIsRefused) {
  Config config = testing::SmallConfig();
  config.output.to_dds = true;
  SessionArgs args;
  args.mode = LoopMode::kRecord;
  args.record_dir = "/nonexistent/never-created";
  args.json = nullptr;
  args.simulation_expected = true;
  args.max_frames = 1;
  ::testing::internal::CaptureStderr();
  EXPECT_EQ(RunSession(config, args), 1);
  const std::string err = ::testing::internal::GetCapturedStderr();
  EXPECT_NE(err.find("built without Cyclone DDS"), std::string::npos) << err;
}
}  // namespace
}  // namespace skyloc::firmware
#endif
