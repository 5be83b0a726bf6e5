// Every device's health counters, read where they are kept (one counters struct per kind
// behind its interface: CameraCounters, ImuCounters, StatusOutputCounters; the simulated
// twins keep them too), shown two ways: a table on stderr at exit and on SIGUSR1, and a
// record in the JSON lines once a second (docs/FIRMWARE.md, "Device counters").
#pragma once

#include <cstddef>
#include <cstdio>

#include "skyloc/drivers/camera.h"
#include "skyloc/drivers/imu_device.h"
#include "skyloc/drivers/status_output.h"

namespace skyloc::firmware {

// The devices of a run; a null one is not there (no IMU without [attitude] kind = iio or
// sim, no status lines with [status] kind = none). The devices must outlive the report.
struct DeviceReport {
  const drivers::Camera* camera = nullptr;
  const drivers::ImuDevice* imu = nullptr;
  const drivers::StatusOutput* status = nullptr;

  // One table, a line per device present.
  void Print(std::FILE* out) const;
  // The JSON lines record, newline included: {"devices":{"timestamp":12.300000,
  // "camera":{"frames":..,"dropped":..,"restarts":..,"errors":..},"imu":{"samples":..,
  // "dropped":..,"errors":..,"outages":..,"reopens":..},"status":{"writes":..,
  // "failures":..}}}, null for a device not there. Returns its length, or 0 when `size`
  // is too small. Allocates nothing.
  std::size_t FormatJson(double timestamp_s, char* line, std::size_t size) const;
};

}  // namespace skyloc::firmware
