// CRC-32 against the published check values (the "123456789" check of the CRC catalogue,
// and values zlib's crc32() gives), plus the continuation property the writer relies on.
#include "skyloc/platform/crc32.h"

#include <gtest/gtest.h>

#include <cstring>
#include <string_view>

namespace skyloc {
namespace {

std::uint32_t CrcOf(std::string_view s, std::uint32_t crc = 0) {
  return Crc32({reinterpret_cast<const std::uint8_t*>(s.data()), s.size()}, crc);
}

TEST(Crc32, PublishedCheckValues) {
  EXPECT_EQ(CrcOf("123456789"), 0xCBF43926u);
  EXPECT_EQ(CrcOf(""), 0x00000000u);
  EXPECT_EQ(CrcOf("a"), 0xE8B7BE43u);
  EXPECT_EQ(CrcOf("The quick brown fox jumps over the lazy dog"), 0x414FA339u);
}

TEST(Crc32, ContinuesAcrossPieces) {
  const std::string_view text = "The quick brown fox jumps over the lazy dog";
  for (std::size_t cut = 0; cut <= text.size(); ++cut)
    EXPECT_EQ(CrcOf(text.substr(cut), CrcOf(text.substr(0, cut))), CrcOf(text)) << cut;
}

TEST(Crc32, DetectsEverySingleBitFlip) {
  std::uint8_t data[64];
  for (std::size_t i = 0; i < sizeof data; ++i)
    data[i] = static_cast<std::uint8_t>(i * 37 + 11);
  const std::uint32_t good = Crc32(data);
  for (std::size_t bit = 0; bit < 8 * sizeof data; ++bit) {
    data[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
    EXPECT_NE(Crc32(data), good) << bit;
    data[bit / 8] ^= static_cast<std::uint8_t>(1u << (bit % 8));
  }
}

}  // namespace
}  // namespace skyloc
