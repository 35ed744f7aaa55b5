/// \file RadixSort.hpp
/// \brief Stable LSD radix sort of (64-bit key, 32-bit index) pairs.
///
/// Keys of a tree are sorted once per step; 11-bit digits give six passes, and a pass
/// whose digit is the same for every key (common: the top bits of Morton keys of a
/// compact cloud) is skipped. Stable, so equal keys keep the input order and the tree
/// is the same on every run.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace pik::detail {

struct KeyIndex {
  std::uint64_t key;
  std::uint32_t index;
};

/// Sorts `a` by key; `scratch` is resized and used as the second buffer.
inline void radix_sort(std::vector<KeyIndex>& a, std::vector<KeyIndex>& scratch) {
  constexpr int bits = 11, passes = (64 + bits - 1) / bits;
  constexpr std::size_t buckets = std::size_t(1) << bits;
  const std::size_t n = a.size();
  if (n < 2) return;
  std::vector<std::array<std::uint32_t, buckets>> hist(passes);
  for (auto& h : hist) h.fill(0);
  for (const KeyIndex& e : a)
    for (int p = 0; p < passes; ++p) ++hist[p][(e.key >> (p * bits)) & (buckets - 1)];
  scratch.resize(n);
  for (int p = 0; p < passes; ++p) {
    auto& h = hist[p];
    bool trivial = false;
    for (std::size_t b = 0; b < buckets; ++b)
      if (h[b] == n) trivial = true;
    if (trivial) continue;
    std::uint32_t sum = 0;
    for (std::size_t b = 0; b < buckets; ++b) {
      std::uint32_t c = h[b];
      h[b] = sum;
      sum += c;
    }
    for (const KeyIndex& e : a) scratch[h[(e.key >> (p * bits)) & (buckets - 1)]++] = e;
    a.swap(scratch);
  }
}

}  // namespace pik::detail
