// libFuzzer target: the configuration parser. Any input either fails with a message or
// yields a Config whose every value is inside the range config/skyloc.toml documents.
#include <cstdint>
#include <cstdlib>
#include <string_view>

#include "firmware/config.h"

namespace {

void Require(bool condition) {
  if (!condition)
    std::abort();  // an accepted configuration broke a documented range
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace skyloc::firmware;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  skyloc::Result<Config> c = ParseConfig(text, "fuzz.toml");
  if (!c.ok()) {
    Require(c.status().message()[0] != '\0');
    return 0;
  }
  Require(c->camera.capture.width >= 16 && c->camera.capture.width <= 8192);
  Require(c->camera.capture.height >= 16 && c->camera.capture.height <= 8192);
  Require(c->camera.capture.fps >= 0.1 && c->camera.capture.fps <= 1000.0);
  Require(!c->camera.device.empty());
  Require(c->segmentation.threshold >= 0 && c->segmentation.threshold <= 254);
  Require(c->descriptor.bands >= 1 && c->descriptor.bands <= 256);
  Require(c->descriptor.rings >= 1 && c->descriptor.longitudes >= 4);
  Require(c->seqslam.ds() >= 1 && c->seqslam.ds() <= 100);
  Require(c->seqslam.openseqslam.sequence_length == c->seqslam.ds());
  Require(c->seqslam.openseqslam.v_min <= c->seqslam.openseqslam.v_max);
  Require(c->capacities.route_frames >= 1 && c->capacities.route_frames <= 1000000);
  Require(c->state.stay_confidence <= c->state.enter_confidence);
  Require(c->realtime.sched_fifo_priority >= 0 && c->realtime.sched_fifo_priority <= 99);
  Require(c->route_db.flush_every >= 1);
  return 0;
}
