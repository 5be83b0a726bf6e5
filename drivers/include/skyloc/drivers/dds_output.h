// [output] kinds = "dds": each frame's localisation on a ROS 2 topic through Eclipse Cyclone
// DDS (Debian's cyclonedds-dev: the DDS ROS 2 Humble and Iron use by default), typed
// skyloc_msgs/msg/Localisation exactly as rmw_cyclonedds_cpp names and lays it out, so
// `ros2 topic echo /skyloc/localisation` works against skyloc_msgs built from the .msg
// this repository ships (docs/OUTPUTS.md). Also /diagnostics
// (diagnostic_msgs/msg/DiagnosticArray) from PublishHealth(), once a second.
//
// QoS: the localisation as ROS 2 sensor data (best effort, keep last 5, volatile); the
// diagnostics as ROS 2's default (reliable, keep last 10), which diagnostic_aggregator
// subscribes with. Built only with SKYLOC_WITH_DDS.
#pragma once

#include <cstdint>

#include "skyloc/drivers/localisation_output.h"

namespace skyloc::drivers {

struct DdsOutputConfig {
  int domain_id = 0;                              // ROS_DOMAIN_ID
  char topic[128] = "rt/skyloc/localisation";     // the DDS topic: "rt" + the ROS 2 topic
  char frame_id[64] = "skyloc";                   // every message's header.frame_id
  char diagnostics_topic[64] = "rt/diagnostics";  // empty: no diagnostics
};

class DdsOutput final : public LocalisationOutput {
 public:
  explicit DdsOutput(const DdsOutputConfig& config);
  ~DdsOutput() override;
  const char* name() const override { return name_; }
  // Creates the participant, topics and writers. Cyclone's own configuration
  // (CYCLONEDDS_URI: interfaces, peers) applies, as it does to ROS 2 nodes.
  Status Open() override;
  void Publish(const LocalisationMessage& message) override;
  void PublishHealth(const char* text) override;
  void Close() override;
  OutputCounters counters() const override { return counters_; }

 private:
  DdsOutputConfig config_;
  char name_[160];
  std::int32_t participant_ = 0;  // dds_entity_t; 0: closed
  std::int32_t writer_ = 0;
  std::int32_t diagnostics_writer_ = 0;
  OutputCounters counters_;
};

}  // namespace skyloc::drivers
