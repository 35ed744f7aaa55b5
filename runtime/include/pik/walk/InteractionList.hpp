/// \file InteractionList.hpp
/// \brief One i-group's interaction list: ranges of j-particles and super-particle ids.
///
/// j-particles are stored as ranges of the tree's sorted EPJ array (a leaf's
/// particles are contiguous), so a list is small, and copying the particles for a
/// kernel call is a few memcpy's. Kept lists let a later step reuse them
/// (ListMode::reuse) after the particles' contents are reloaded.
#pragma once

#include <cstdint>
#include <vector>

#include "pik/tree/IndexRange.hpp"

namespace pik {

struct InteractionList {
  std::vector<IndexRange> epj;      ///< ranges of the sorted EPJ array
  std::vector<std::uint32_t> spj;   ///< indices of super-particles (cells, then imported)

  void clear() {
    epj.clear();
    spj.clear();
  }
  /// Appends a range, merging it with the previous one when they touch.
  void add_epj(std::uint32_t b, std::uint32_t e) {
    if (b == e) return;
    if (!epj.empty() && epj.back().end == b) {
      epj.back().end = e;
    } else {
      epj.push_back({b, e});
    }
  }
  std::size_t epj_count() const {
    std::size_t n = 0;
    for (const IndexRange& r : epj) n += r.end - r.begin;
    return n;
  }
};

}  // namespace pik
