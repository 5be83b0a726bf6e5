// Fixed-width values in the records of skyloc's files (route database, FAB-MAP vocabulary):
// copied byte for byte in the machine's order, little-endian on every target skyloc builds
// for (x86-64, aarch64, armhf), which the formats document (docs/ROUTE_DB.md, FABMAP.md).
// memcpy, not a cast: records are unaligned.
#pragma once

#include <bit>
#include <cstdint>
#include <cstring>
#include <type_traits>

namespace skyloc {

// A big-endian port would add byte swaps here.
static_assert(std::endian::native == std::endian::little,
              "skyloc's file formats are little-endian");

template <typename T>
void StoreBytes(std::uint8_t* p, T v) {
  static_assert(std::is_trivially_copyable_v<T>);
  std::memcpy(p, &v, sizeof v);
}

template <typename T>
T LoadBytes(const std::uint8_t* p) {
  static_assert(std::is_trivially_copyable_v<T>);
  T v;
  std::memcpy(&v, p, sizeof v);
  return v;
}

}  // namespace skyloc
