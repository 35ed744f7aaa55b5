// pik::io::crc32 (zlib's) against the CRC-32 check value and the table-driven
// definition pik used before it called zlib, and an old file that must stay readable.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <pik/io/BinarySnapshot.hpp>
#include <pik/io/Crc32.hpp>

namespace {

// The reflected CRC-32 bit by bit (polynomial 0xEDB88320, initial and final XOR
// 0xFFFFFFFF), as specified for ISO 3309 / PNG: the oracle.
std::uint32_t crc32_bitwise(const unsigned char* p, std::size_t n, std::uint32_t crc = 0) {
  crc = ~crc;
  for (std::size_t i = 0; i < n; ++i) {
    crc ^= p[i];
    for (int k = 0; k < 8; ++k) crc = (crc & 1u) ? 0xEDB88320u ^ (crc >> 1) : crc >> 1;
  }
  return ~crc;
}

TEST(Crc32, CheckValue) {
  // The standard check value of CRC-32 over the ASCII digits "123456789".
  const std::string s = "123456789";
  EXPECT_EQ(pik::io::crc32(s.data(), s.size()), 0xCBF43926u);
  EXPECT_EQ(pik::io::crc32(nullptr, 0), 0u);
}

TEST(Crc32, MatchesTheDefinitionAndContinues) {
  std::mt19937 rng(7);
  for (std::size_t n : {1u, 7u, 8u, 9u, 63u, 1000u, 100003u}) {
    std::vector<unsigned char> v(n);
    for (auto& c : v) c = static_cast<unsigned char>(rng());
    const std::uint32_t whole = pik::io::crc32(v.data(), n);
    EXPECT_EQ(whole, crc32_bitwise(v.data(), n)) << n;
    const std::size_t cut = n / 3;
    EXPECT_EQ(pik::io::crc32(v.data() + cut, n - cut, pik::io::crc32(v.data(), cut)), whole) << n;
  }
}

TEST(Crc32, FileWrittenBeforeZlibStaysReadable) {
  // tests/python/data/crc_v1.pbin was written with the hand-written slicing-by-8 CRC.
  const pik::io::Snapshot s = pik::io::read_binary(PIK_TEST_DATA "/crc_v1.pbin");
  ASSERT_EQ(s.size(), 16u);
  EXPECT_EQ(s.id[5], 38u);
  EXPECT_EQ(s.step, 32u);
  EXPECT_EQ(s.attr.get_string("theta"), "0.5");
  pik::io::write_binary(PIK_TEST_BINARY "/crc_v1_rewritten.pbin", s);
  EXPECT_TRUE(pik::io::same_bits(s, pik::io::read_binary(PIK_TEST_BINARY "/crc_v1_rewritten.pbin")));
}

}  // namespace
