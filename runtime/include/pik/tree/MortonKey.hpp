/// \file MortonKey.hpp
/// \brief 64-bit Morton (Z-order) keys: 21 levels in 3D, 31 in 2D, relative to a cube.
///
/// Sorting particles by the interleaved bits of their quantised coordinates puts every
/// octree cell's particles in one contiguous range, which is how the tree is built
/// without pointers (Warren and Salmon 1993, "A parallel hashed oct-tree N-body
/// algorithm"). A key frame is the cube the keys are relative to; the tree makes a new
/// frame for a cell whose particles are still together after the last key level, so
/// clustering deeper than 2^-21 of the root is still resolved.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <type_traits>

// BMI2's pdep deposits the bits in one instruction (3 cycles on Intel since Haswell
// and AMD since Zen 3); Zen 1 and 2 microcode it (~250 cycles), so they keep the shifts.
#if defined(__x86_64__) && (defined(__GNUC__) || defined(__clang__))
#include <immintrin.h>
#define PIK_MORTON_HAS_PDEP 1
#if defined(__BMI2__) && !defined(__znver1__) && !defined(__znver2__)
#define PIK_MORTON_PDEP 1
#endif
#endif

namespace pik {

template <int D>
struct MortonKey {
  static_assert(D == 2 || D == 3, "pik: Morton keys are defined for 2 and 3 dimensions");
  /// Levels below the frame cube that one key resolves.
  static constexpr int levels = D == 3 ? 21 : 31;
  static constexpr std::uint64_t cells_per_side = std::uint64_t(1) << levels;
  static constexpr int children = 1 << D;

  /// Interleaves D quantised coordinates, each in [0, 2^levels).
  static constexpr std::uint64_t encode(const std::uint64_t (&q)[D]) {
#ifdef PIK_MORTON_PDEP
    if (!std::is_constant_evaluated()) return encode_pdep(q);
#endif
    return encode_by_shifts(q);
  }
  /// The same by shifts and masks (what encode() does without BMI2, and at compile time).
  static constexpr std::uint64_t encode_by_shifts(const std::uint64_t (&q)[D]) {
    if constexpr (D == 3) {
      return spread3(q[0]) << 2 | spread3(q[1]) << 1 | spread3(q[2]);
    } else {
      return spread2(q[0]) << 1 | spread2(q[1]);
    }
  }
#ifdef PIK_MORTON_HAS_PDEP
  /// The same by BMI2's pdep (callable only on a CPU with BMI2; encode() uses it when
  /// the build targets one).
  [[gnu::target("bmi2")]] static std::uint64_t encode_pdep(const std::uint64_t (&q)[D]) {
    if constexpr (D == 3) {
      return _pdep_u64(q[0], 0x4924924924924924ULL) | _pdep_u64(q[1], 0x2492492492492492ULL) |
             _pdep_u64(q[2], 0x1249249249249249ULL);
    } else {
      return _pdep_u64(q[0], 0x2aaaaaaaaaaaaaaaULL) | _pdep_u64(q[1], 0x1555555555555555ULL);
    }
  }
#endif
  /// Child octant (0 .. 2^D-1) that a key falls into when splitting a cell at `depth`
  /// (depth 0 = the frame cube).
  static constexpr unsigned digit(std::uint64_t key, int depth) {
    return unsigned(key >> (D * (levels - 1 - depth))) & (children - 1);
  }

 private:
  static constexpr std::uint64_t spread3(std::uint64_t v) {
    v &= 0x1fffff;
    v = (v | v << 32) & 0x1f00000000ffffULL;
    v = (v | v << 16) & 0x1f0000ff0000ffULL;
    v = (v | v << 8) & 0x100f00f00f00f00fULL;
    v = (v | v << 4) & 0x10c30c30c30c30c3ULL;
    v = (v | v << 2) & 0x1249249249249249ULL;
    return v;
  }
  static constexpr std::uint64_t spread2(std::uint64_t v) {
    v &= 0x7fffffff;
    v = (v | v << 16) & 0x0000ffff0000ffffULL;
    v = (v | v << 8) & 0x00ff00ff00ff00ffULL;
    v = (v | v << 4) & 0x0f0f0f0f0f0f0f0fULL;
    v = (v | v << 2) & 0x3333333333333333ULL;
    v = (v | v << 1) & 0x5555555555555555ULL;
    return v;
  }
};

/// The cube [lo, lo + side)^D that keys are relative to, computed in double so that
/// float particles spread over 1e-30 .. 1e30 still get distinct keys where double can
/// tell them apart.
template <int D>
struct KeyFrame {
  double lo[D] = {};
  double side = 1;

  /// The child-octant cube `digit` of this cube.
  constexpr KeyFrame child(unsigned digit) const {
    KeyFrame c;
    c.side = side * 0.5;
    for (int d = 0; d < D; ++d) c.lo[d] = lo[d] + ((digit >> (D - 1 - d)) & 1u) * c.side;
    return c;
  }
  template <class V>
  std::uint64_t key(const V& p) const {
    const double scale = double(MortonKey<D>::cells_per_side) / side;
    const double top = double(MortonKey<D>::cells_per_side - 1);
    std::uint64_t q[D];
    for (int d = 0; d < D; ++d) {
      double x = std::floor((double(p[d]) - lo[d]) * scale);
      q[d] = std::uint64_t(std::clamp(x, 0.0, top));
    }
    return MortonKey<D>::encode(q);
  }
};

}  // namespace pik
