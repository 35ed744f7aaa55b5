/// \file RadixSort.hpp
/// \brief Stable LSD radix sort of (64-bit key, 32-bit index) pairs, on all threads,
/// and a sort for input that is nearly in order already (a rebuild's warm start).
///
/// Keys of a tree are sorted once per step; 11-bit digits give six passes, and a pass
/// whose digit is the same for every key (common: the top bits of Morton keys of a
/// compact cloud) is skipped. Only the top digits are sorted by passes, enough bits
/// (about log2 n + 10) that keys sharing them are rare: the runs of keys that do are
/// then sorted by insertion (or by a stable merge sort when long, as in a tight
/// cluster). For 2^20 Morton keys that is three passes instead of six. Stable, so
/// equal keys keep the input order and the tree is the same on every run. Threads take fixed contiguous blocks of the input, count
/// digits per block, and scatter their block to offsets ordered by (digit, block):
/// the result is the serial sort's, whatever the number of threads.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
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
  // First pass to do: the passes below it only order keys whose top bits agree.
  const int lg = std::bit_width(n);
  const int p0 = std::clamp((64 - lg - 10) / bits, 0, 3);
  using Hist = std::array<std::uint32_t, buckets>;
  // hist[b * passes + p]: digit counts of pass p in block b.
  std::vector<Hist> hist(nb * passes);
  parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
    Hist* h = &hist[std::size_t(b) * passes];
    for (int p = p0; p < passes; ++p) h[p].fill(0);
    for (std::size_t i = block_begin(std::size_t(b)); i < block_begin(std::size_t(b) + 1); ++i)
      for (int p = p0; p < passes; ++p) ++h[p][(a[i].key >> (p * bits)) & (buckets - 1)];
  });
  scratch.resize(n);
  for (int p = p0; p < passes; ++p) {
    // Skip a pass whose digit is the same for all keys.
    bool trivial = false;
    for (std::size_t d = 0; d < buckets && !trivial; ++d) {
      std::size_t total = 0;
      for (std::size_t b = 0; b < nb; ++b) total += hist[b * passes + p][d];
      trivial = total == n;
    }
    if (trivial) continue;
    // Block counts of this pass's digit, measured on the current order of `a`.
    if (p > p0 && nb > 1) {
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
  if (p0 == 0) return;
  // Runs of keys equal in the sorted top bits, in input order: sorted stably by the
  // whole key. Block b takes the runs that start in [first[b], first[b + 1]), first[b]
  // the first run start at or after its beginning (found before anything moves).
  const int shift = p0 * bits;
  std::vector<std::size_t> first(nb + 1, n);
  parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
    std::size_t i = block_begin(std::size_t(b));
    while (i > 0 && i < n && a[i].key >> shift == a[i - 1].key >> shift) ++i;
    first[std::size_t(b)] = i;
  });
  parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
    std::size_t i = first[std::size_t(b)];
    const std::size_t stop = first[std::size_t(b) + 1];
    while (i < stop) {
      const std::uint64_t t = a[i].key >> shift;
      std::size_t e = i + 1;
      while (e < stop && a[e].key >> shift == t) ++e;
      if (e - i > 32) {
        std::stable_sort(a.begin() + std::ptrdiff_t(i), a.begin() + std::ptrdiff_t(e),
                         [](const KeyIndex& x, const KeyIndex& y) { return x.key < y.key; });
      } else {
        for (std::size_t k = i + 1; k < e; ++k) {
          const KeyIndex v = a[k];
          std::size_t m = k;
          for (; m > i && a[m - 1].key > v.key; --m) a[m] = a[m - 1];
          a[m] = v;
        }
      }
      i = e;
    }
  });
}

/// Orders by key, then index: for keys with distinct indices that is the order
/// radix_sort gives keys listed in index order (it is stable).
inline bool key_index_less(const KeyIndex& x, const KeyIndex& y) {
  return (x.key < y.key) | ((x.key == y.key) & (x.index < y.index));
}

/// Sorts `a` by (key, index) when it is nearly in that order already (the keys of
/// particles listed in the previous step's sorted order, after they moved a little):
/// one pass keeps a sorted subsequence, putting both elements of every descent aside
/// (at most twice the fewest elements whose removal leaves `a` sorted), the few put
/// aside are sorted, and the two are merged. Returns false, with `a` scrambled, when
/// more than `max_aside` elements would have to be put aside: the caller then sorts
/// from scratch. Indices must be distinct, so the result is unique.
inline bool sort_nearly_sorted(std::vector<KeyIndex>& a, std::vector<KeyIndex>& scratch,
                               std::vector<KeyIndex>& aside, std::size_t max_aside) {
  const std::size_t n = a.size();
  aside.clear();
  if (n < 2) return true;
  KeyIndex* p = a.data();
  std::size_t m = 1;  // p[0, m): the kept sorted subsequence (compacted in place)
  KeyIndex last = p[0];
  for (std::size_t i = 1; i < n; ++i) {
    const KeyIndex x = p[i];
    if (m > 0 && key_index_less(x, last)) [[unlikely]] {
      aside.push_back(last);
      aside.push_back(x);
      if (aside.size() > max_aside) return false;
      --m;
      if (m > 0) last = p[m - 1];
    } else {
      p[m++] = x;
      last = x;
    }
  }
  if (aside.empty()) return true;
  std::sort(aside.begin(), aside.end(), key_index_less);
  scratch.resize(n);
  std::merge(p, p + m, aside.begin(), aside.end(), scratch.begin(), key_index_less);
  a.swap(scratch);
  return true;
}

}  // namespace pik::detail
