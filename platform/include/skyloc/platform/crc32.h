// CRC-32 (IEEE 802.3 / zlib / PNG: reflected polynomial 0xEDB88320, init and final XOR
// 0xFFFFFFFF), table-driven. Our own 30 lines rather than zlib's crc32(): zlib would be one
// more multiarch package the ARM cross builds must install in step with the host's (the
// archive does not always publish them together, see docs/ARCHITECTURE.md), for a function
// whose published check value ("123456789" -> 0xCBF43926) pins it down completely.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>

namespace skyloc {

// CRC of `bytes`, continuing from `crc` (the CRC of the bytes before them; 0 to start):
//   Crc32(b, Crc32(a)) == Crc32(a followed by b)
std::uint32_t Crc32(std::span<const std::uint8_t> bytes, std::uint32_t crc = 0);

}  // namespace skyloc
