// libFuzzer target: the route database loader. Any input is either rejected with a
// message or loads frames that fit the capacity; it never crashes or reads out of bounds.
//
// Two ways to read an input, chosen by its first byte, so both shallow and deep paths get
// explored: (even) the bytes are a file as they are; (odd) they are edits to a valid
// route file written by RouteDbWriter at start-up (with 9-column horizon strips, packed at
// 4 bits a column as the current format stores them): (offset lo, offset hi, value) triples,
// and with bit 1 set a truncation to a length taken from the second byte. The fuzzing
// build (FUZZING_BUILD_MODE_UNSAFE_FOR_PRODUCTION) also skips the CRC comparisons in
// route_db.cpp, so edits are not all stopped by the checksums.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iterator>
#include <span>
#include <string>
#include <vector>

#include "firmware/route_db.h"

namespace {

constexpr std::size_t kColumns = 9;  // odd: a packed strip ends in half a byte

std::vector<std::uint8_t> ValidRouteFile() {
  using namespace skyloc::firmware;
  const std::string path = "/tmp/skyloc_route_fuzz_" + std::to_string(::getpid()) + ".db";
  RouteDbSettings settings;
  settings.descriptor_kind = 1;
  settings.bands = 4;
  settings.dim = 4;
  settings.lens.known = true;  // a version-3 lens record for the edits to reach
  settings.lens.width = 64;
  settings.lens.height = 48;
  settings.lens.fov_deg = 185;
  settings.strip = {static_cast<std::uint32_t>(kColumns), 4, 0, 2000};
  RouteDbWriter writer;
  if (!writer.Create(path.c_str(), settings, 3, true).ok())
    std::abort();
  for (int i = 0; i < 7; ++i) {
    RouteFrameMeta meta;
    meta.timestamp_ns = static_cast<std::uint64_t>(i);
    if (i % 2 == 0)
      meta.pose = skyloc::drivers::Pose{1, 2, 3, 4, 5, 6};
    const float d[4] = {static_cast<float>(i), 1, 2, 3};
    std::uint8_t strip[kColumns];
    for (std::size_t j = 0; j < kColumns; ++j)
      strip[j] = static_cast<std::uint8_t>(40 * static_cast<std::size_t>(i) + 9 * j);
    if (!writer.Append(meta, d, strip).ok())
      std::abort();
  }
  if (!writer.Commit().ok())
    std::abort();
  std::ifstream in(path, std::ios::binary);
  std::vector<std::uint8_t> bytes{std::istreambuf_iterator<char>(in),
                                  std::istreambuf_iterator<char>()};
  std::remove(path.c_str());
  return bytes;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace skyloc::firmware;
  static const std::vector<std::uint8_t> kValid = ValidRouteFile();
  static RouteFrames frames;
  static const bool allocated = frames.Allocate(64, 4, kColumns).ok();
  if (!allocated)
    std::abort();

  std::vector<std::uint8_t> edited;
  std::span<const std::uint8_t> bytes(data, size);
  if (size >= 1 && (data[0] & 1u) != 0) {
    edited = kValid;
    for (std::size_t i = 1; i + 2 < size; i += 3) {
      const std::size_t offset = (data[i] | (std::size_t{data[i + 1]} << 8)) % edited.size();
      edited[offset] = data[i + 2];
    }
    if ((data[0] & 2u) != 0 && size >= 2)
      edited.resize(std::size_t{data[1]} * edited.size() / 256);
    bytes = edited;
  }

  for (RouteDbLoadPolicy policy :
       {RouteDbLoadPolicy::kStrict, RouteDbLoadPolicy::kRecoverInterrupted,
        RouteDbLoadPolicy::kSalvage}) {
    RouteDbLoadReport report;
    const skyloc::Status s = ParseRouteDb(bytes, nullptr, policy, &frames, &report);
    if (!s.ok()) {
      if (s.message()[0] == '\0')
        std::abort();
      continue;
    }
    if (frames.size() > frames.capacity() || report.frames != frames.size() ||
        report.valid_bytes + report.dropped_bytes > bytes.size())
      std::abort();
    // Touch every loaded value: ASan catches a record read past the input.
    float sum = 0;
    for (std::size_t i = 0; i < frames.size(); ++i) {
      for (float v : frames.descriptor(i))
        sum += v;
      for (std::uint8_t v : frames.strip(i))
        sum += v;
    }
    volatile float sink = sum;
    (void)sink;
  }
  return 0;
}
