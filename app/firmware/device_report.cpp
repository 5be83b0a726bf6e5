#include "firmware/device_report.h"

namespace skyloc::firmware {
namespace {

using ull = unsigned long long;

}  // namespace

void DeviceReport::Print(std::FILE* out) const {
  std::fprintf(out, "%-7s %-32s %s\n", "device", "name", "counters");
  if (camera != nullptr) {
    const drivers::CameraCounters& c = camera->counters();
    std::fprintf(out, "%-7s %-32s frames %llu, dropped %llu, restarts %llu, errors %llu\n",
                 "camera", camera->info().name, static_cast<ull>(c.frames),
                 static_cast<ull>(c.dropped), static_cast<ull>(c.restarts),
                 static_cast<ull>(c.errors));
  }
  if (imu != nullptr) {
    const drivers::ImuCounters& c = imu->counters();
    std::fprintf(out,
                 "%-7s %-32s samples %llu, dropped %llu, outages %llu, reopens %llu, errors "
                 "%llu\n",
                 "imu", imu->info().name, static_cast<ull>(c.samples), static_cast<ull>(c.dropped),
                 static_cast<ull>(c.outages), static_cast<ull>(c.reopens),
                 static_cast<ull>(c.errors));
  }
  if (status != nullptr) {
    const drivers::StatusOutputCounters& c = status->counters();
    std::fprintf(out, "%-7s %-32s writes %llu, failures %llu\n", "status", status->name(),
                 static_cast<ull>(c.writes), static_cast<ull>(c.failures));
  }
}

std::size_t DeviceReport::FormatJson(double timestamp_s, char* line, std::size_t size) const {
  char camera_json[160] = "null", imu_json[192] = "null", status_json[64] = "null";
  if (camera != nullptr) {
    const drivers::CameraCounters& c = camera->counters();
    std::snprintf(camera_json, sizeof camera_json,
                  "{\"frames\":%llu,\"dropped\":%llu,\"restarts\":%llu,\"errors\":%llu}",
                  static_cast<ull>(c.frames), static_cast<ull>(c.dropped),
                  static_cast<ull>(c.restarts), static_cast<ull>(c.errors));
  }
  if (imu != nullptr) {
    const drivers::ImuCounters& c = imu->counters();
    std::snprintf(imu_json, sizeof imu_json,
                  "{\"samples\":%llu,\"dropped\":%llu,\"errors\":%llu,\"outages\":%llu,"
                  "\"reopens\":%llu}",
                  static_cast<ull>(c.samples), static_cast<ull>(c.dropped),
                  static_cast<ull>(c.errors), static_cast<ull>(c.outages),
                  static_cast<ull>(c.reopens));
  }
  if (status != nullptr) {
    const drivers::StatusOutputCounters& c = status->counters();
    std::snprintf(status_json, sizeof status_json, "{\"writes\":%llu,\"failures\":%llu}",
                  static_cast<ull>(c.writes), static_cast<ull>(c.failures));
  }
  const int n = std::snprintf(
      line, size, "{\"devices\":{\"timestamp\":%.6f,\"camera\":%s,\"imu\":%s,\"status\":%s}}\n",
      timestamp_s, camera_json, imu_json, status_json);
  return n > 0 && static_cast<std::size_t>(n) < size ? static_cast<std::size_t>(n) : 0;
}

}  // namespace skyloc::firmware
