#include "skyloc/drivers/dds_output.h"

#include <dds/dds.h>

#include <cstdio>
#include <cstring>
#include <ctime>

#include "ros2_types.h"

namespace skyloc::drivers {
namespace {

static_assert(sizeof(dds_entity_t) == sizeof(std::int32_t), "dds_entity_t is kept as int32_t");

builtin_interfaces_msg_dds__Time_ TimeOf(std::int64_t ns) {
  builtin_interfaces_msg_dds__Time_ t{};
  t.sec = static_cast<std::int32_t>(ns / 1000000000);
  t.nanosec = static_cast<std::uint32_t>(ns % 1000000000);
  return t;
}

Status DdsError(dds_return_t code, const char* name, const char* what) {
  return Status::Error(StatusCode::kUnavailable,
                       "%s: %s failed: %s (Cyclone DDS; its configuration is CYCLONEDDS_URI)", name,
                       what, dds_strretcode(code));
}

}  // namespace

DdsOutput::DdsOutput(const DdsOutputConfig& config) : config_(config) {
  std::snprintf(name_, sizeof name_, "dds %s (domain %d)", config_.topic, config_.domain_id);
}

DdsOutput::~DdsOutput() {
  Close();
}

Status DdsOutput::Open() {
  if (participant_ > 0)
    return Status::Error(StatusCode::kFailedPrecondition, "%s is already open", name_);
  const dds_entity_t participant =
      dds_create_participant(static_cast<dds_domainid_t>(config_.domain_id), nullptr, nullptr);
  if (participant < 0)
    return DdsError(participant, name_, "creating the participant");
  participant_ = participant;
  const dds_entity_t topic = dds_create_topic(participant, &skyloc_msgs_msg_dds__Localisation__desc,
                                              config_.topic, nullptr, nullptr);
  if (topic < 0) {
    Close();
    return DdsError(topic, name_, "creating the topic");
  }
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_BEST_EFFORT, 0);
  dds_qset_history(qos, DDS_HISTORY_KEEP_LAST, 5);
  dds_qset_durability(qos, DDS_DURABILITY_VOLATILE);
  writer_ = dds_create_writer(participant, topic, qos, nullptr);
  dds_delete_qos(qos);
  if (writer_ < 0) {
    const dds_return_t e = writer_;
    Close();
    return DdsError(e, name_, "creating the writer");
  }
  if (config_.diagnostics_topic[0] != '\0') {
    const dds_entity_t diagnostics =
        dds_create_topic(participant, &diagnostic_msgs_msg_dds__DiagnosticArray__desc,
                         config_.diagnostics_topic, nullptr, nullptr);
    dds_qos_t* reliable = dds_create_qos();
    dds_qset_reliability(reliable, DDS_RELIABILITY_RELIABLE, DDS_MSECS(100));
    dds_qset_history(reliable, DDS_HISTORY_KEEP_LAST, 10);
    diagnostics_writer_ = diagnostics < 0
                              ? diagnostics
                              : dds_create_writer(participant, diagnostics, reliable, nullptr);
    dds_delete_qos(reliable);
    if (diagnostics_writer_ < 0) {
      const dds_return_t e = diagnostics_writer_;
      Close();
      return DdsError(e, name_, "creating the /diagnostics writer");
    }
  }
  return Status::Ok();
}

void DdsOutput::Publish(const LocalisationMessage& m) {
  if (participant_ <= 0)
    return;
  ++counters_.published;
  skyloc_msgs_msg_dds__Localisation_ sample{};
  sample.header.stamp = TimeOf(m.timestamp_ns);
  sample.header.frame_id = config_.frame_id;
  sample.state = m.state;
  sample.confidence = m.confidence;
  sample.uniqueness = m.uniqueness;
  sample.frame = m.frame;
  sample.route_index = m.route_index;
  sample.route_length = m.route_length;
  sample.distance_along_route_m = m.distance_along_m;
  sample.heading_deg = m.heading_deg;
  sample.heading_confidence = m.heading_confidence;
  sample.latency_us = m.latency_us;
  if (dds_write(writer_, &sample) != DDS_RETCODE_OK)
    ++counters_.dropped;
}

void DdsOutput::PublishHealth(const char* text) {
  if (participant_ <= 0 || diagnostics_writer_ <= 0)
    return;
  // "key=value" lines into KeyValue pairs, pointing into a copy of the text.
  constexpr int kMaxValues = 32;
  char copy[1024];
  std::snprintf(copy, sizeof copy, "%s", text);
  diagnostic_msgs_msg_dds__KeyValue_ values[kMaxValues];
  std::uint32_t n = 0;
  for (char* line = copy; line != nullptr && *line != '\0' && n < kMaxValues;) {
    char* end = std::strchr(line, '\n');
    if (end != nullptr)
      *end = '\0';
    if (char* eq = std::strchr(line, '='); eq != nullptr) {
      *eq = '\0';
      values[n].key = line;
      values[n].value = eq + 1;
      ++n;
    }
    line = end != nullptr ? end + 1 : nullptr;
  }
  char hardware_id[] = "skyloc";
  char status_name[] = "skyloc: localisation";
  char message[] = "running";
  diagnostic_msgs_msg_dds__DiagnosticStatus_ status{};
  status.level = diagnostic_msgs_msg_dds__DiagnosticStatus_Constants_OK;
  status.name = status_name;
  status.message = message;
  status.hardware_id = hardware_id;
  status.values._length = status.values._maximum = n;
  status.values._buffer = values;
  diagnostic_msgs_msg_dds__DiagnosticArray_ array{};
  timespec now{};
  ::clock_gettime(CLOCK_REALTIME, &now);
  array.header.stamp = TimeOf(static_cast<std::int64_t>(now.tv_sec) * 1000000000 + now.tv_nsec);
  array.header.frame_id = config_.frame_id;
  array.status._length = array.status._maximum = 1;
  array.status._buffer = &status;
  (void)dds_write(diagnostics_writer_, &array);
}

void DdsOutput::Close() {
  if (participant_ > 0)
    (void)dds_delete(participant_);  // with its topics and writers
  participant_ = writer_ = diagnostics_writer_ = 0;
}

}  // namespace skyloc::drivers
