/// \file RadixSort.hpp
/// \brief Stable LSD radix sort of (64-bit key, 32-bit index) pairs, on all threads.
///
/// Keys of a tree are sorted once per step; 11-bit digits give six passes, and a pass
/// whose digit is the same for every key (common: the top bits of Morton keys of a
/// compact cloud) is skipped. Stable, so equal keys keep the input order and the tree
/// is the same on every run. Threads take fixed contiguous blocks of the input, count
/// digits per block, and scatter their block to offsets ordered by (digit, block):
/// the result is the serial sort's, whatever the number of threads.
#pragma once

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "pik/detail/Threads.hpp"

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
  // Blocks of at least 16384 keys (below that, threads cost more than they save).
  const std::size_t nb = std::clamp<std::size_t>(n / 16384, 1, std::size_t(max_threads()));
  auto block_begin = [&](std::size_t b) { return n * b / nb; };
  using Hist = std::array<std::uint32_t, buckets>;
  // hist[b * passes + p]: digit counts of pass p in block b.
  std::vector<Hist> hist(nb * passes);
  parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
    Hist* h = &hist[std::size_t(b) * passes];
    for (int p = 0; p < passes; ++p) h[p].fill(0);
    for (std::size_t i = block_begin(std::size_t(b)); i < block_begin(std::size_t(b) + 1); ++i)
      for (int p = 0; p < passes; ++p) ++h[p][(a[i].key >> (p * bits)) & (buckets - 1)];
  });
  scratch.resize(n);
  for (int p = 0; p < passes; ++p) {
    // Skip a pass whose digit is the same for all keys.
    bool trivial = false;
    for (std::size_t d = 0; d < buckets && !trivial; ++d) {
      std::size_t total = 0;
      for (std::size_t b = 0; b < nb; ++b) total += hist[b * passes + p][d];
      trivial = total == n;
    }
    if (trivial) continue;
    // Block counts of this pass's digit, measured on the current order of `a`.
    if (p > 0 && nb > 1) {
      parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
        Hist& h = hist[std::size_t(b) * passes + p];
        h.fill(0);
        for (std::size_t i = block_begin(std::size_t(b)); i < block_begin(std::size_t(b) + 1); ++i)
          ++h[(a[i].key >> (p * bits)) & (buckets - 1)];
      });
    }
    // Offsets: digit-major, block-minor.
    std::uint32_t sum = 0;
    for (std::size_t d = 0; d < buckets; ++d)
      for (std::size_t b = 0; b < nb; ++b) {
        std::uint32_t c = hist[b * passes + p][d];
        hist[b * passes + p][d] = sum;
        sum += c;
      }
    parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
      Hist& h = hist[std::size_t(b) * passes + p];
      for (std::size_t i = block_begin(std::size_t(b)); i < block_begin(std::size_t(b) + 1); ++i)
        scratch[h[(a[i].key >> (p * bits)) & (buckets - 1)]++] = a[i];
    });
    a.swap(scratch);
  }
}

}  // namespace pik::detail
