/// \file Crc32.hpp
/// \brief CRC-32 (the zlib/PNG polynomial 0xEDB88320) for snapshot checksums, by zlib.
///
/// zlib's crc32_z (ISO 3309 / ITU-T V.42 CRC-32, the one of gzip and PNG): the same
/// checksum as Python's `zlib.crc32`, so tools outside C++ verify a pik binary
/// snapshot without extra code, and files written by pik's earlier hand-written
/// implementation read back unchanged (tests/python/test_crc32.cpp). Programs link
/// zlib through pik::runtime (ZLIB::ZLIB).
#pragma once

#include <zlib.h>

#include <cstddef>
#include <cstdint>

namespace pik::io {

/// Continues a CRC-32 over `n` more bytes; start with `crc = 0`.
inline std::uint32_t crc32(const void* data, std::size_t n, std::uint32_t crc = 0) {
  // crc32_z takes a size_t length (crc32 only 32 bits); a null pointer with n = 0
  // would return the initial value, so pass some address for empty input.
  static const unsigned char none = 0;
  const auto* p = n ? static_cast<const Bytef*>(data) : &none;
  return std::uint32_t(::crc32_z(uLong(crc), p, z_size_t(n)));
}

}  // namespace pik::io
