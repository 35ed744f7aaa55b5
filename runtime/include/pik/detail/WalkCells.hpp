/// \file WalkCells.hpp
/// \brief What the long-range group walk reads of each cell, as structure of arrays.
///
/// The walk judges the children of an opened cell all at once (they are contiguous
/// in the cell array): for each, is it far enough to be used whole, a leaf, or to be
/// opened? Keeping the few numbers the test needs in separate arrays (box, reference
/// point, opening radius) lets the compiler judge all 2^D siblings with one vector
/// operation per quantity (8 doubles: one AVX-512 register in 3D) instead of one
/// branchy scalar test per cell, and makes the outcome three bit masks. The arrays
/// are padded by 2^D entries so a block of siblings can always be read whole.
#pragma once

#include <cstdint>
#include <limits>
#include <vector>

#include "pik/Box.hpp"

namespace pik::detail {

template <int D>
class WalkCells {
 public:
  static constexpr int lanes = 1 << D;

  /// Outcome of judging one block of siblings: bit l stands for cell first + l.
  struct Verdict {
    unsigned far = 0;   ///< use whole (super-particle)
    unsigned leaf = 0;  ///< a leaf that is not far: its particles join the list
    unsigned open = 0;  ///< an inner cell that is not far: visit its children
  };

  /// Sizes the arrays for `n` cells (plus padding; padding cells are never used).
  void resize(std::size_t n) {
    const std::size_t m = n + lanes;
    for (int d = 0; d < D; ++d) lo_[d].assign(m, 0.0), hi_[d].assign(m, 0.0), ref_[d].assign(m, 0.0);
    open2_.assign(m, std::numeric_limits<double>::infinity());
    child_.assign(m, 0);
    n_child_.assign(m, 0);
    leaf_end_.assign(m, 0);
    mixed_.assign(m, 0);
    size_ = n;
  }
  std::size_t size() const { return size_; }

  /// Cell c: tight box, the point distances are measured to (unused when the
  /// distance is to the box), squared opening radius, children. A leaf (n_child 0)
  /// records its local particles [child, leaf_end) and whether it holds imported
  /// items too (`mixed`: the walk then reads the tree's cell for their ranges).
  void set(std::size_t c, const Box<double, D>& box, const Vec<double, D>& ref, double open2,
           std::uint32_t child, std::uint32_t n_child, std::uint32_t leaf_end = 0, bool mixed = false) {
    for (int d = 0; d < D; ++d) lo_[d][c] = box.lo[d], hi_[d][c] = box.hi[d], ref_[d][c] = ref[d];
    open2_[c] = open2;
    child_[c] = child;
    n_child_[c] = n_child;
    leaf_end_[c] = leaf_end;
    mixed_[c] = mixed;
  }
  std::uint32_t child(std::size_t c) const { return child_[c]; }
  std::uint32_t n_child(std::size_t c) const { return n_child_[c]; }
  /// A leaf's local particles, as a range of the sorted local particles.
  std::uint32_t leaf_begin(std::size_t c) const { return child_[c]; }
  std::uint32_t leaf_end(std::size_t c) const { return leaf_end_[c]; }
  bool mixed(std::size_t c) const { return mixed_[c] != 0; }

  /// Judges cells [first, first + n), n <= lanes, against an i-group's box: a cell
  /// is far when its box does not overlap the group's and the squared distance from
  /// the group's box to the cell's box (to_box) or reference point exceeds open2.
  template <bool to_box>
  Verdict judge(const Box<double, D>& g, std::uint32_t first, std::uint32_t n) const {
    alignas(64) std::int64_t far[lanes], leaf[lanes];
    for (int l = 0; l < lanes; ++l) {
      const std::size_t c = first + std::size_t(l);
      double d2 = 0;
      bool apart = false;
      for (int d = 0; d < D; ++d) {
        const double lo = lo_[d][c], hi = hi_[d][c];
        const double a = to_box ? g.lo[d] - hi : g.lo[d] - ref_[d][c];
        const double b = to_box ? lo - g.hi[d] : ref_[d][c] - g.hi[d];
        const double e = std::max(std::max(a, b), 0.0);
        d2 += e * e;
        apart = apart | (hi < g.lo[d]) | (g.hi[d] < lo);
      }
      far[l] = apart & (d2 > open2_[c]);
      leaf[l] = n_child_[c] == 0;
    }
    unsigned f = 0, lf = 0;
    for (int l = 0; l < lanes; ++l) f |= unsigned(far[l]) << l, lf |= unsigned(leaf[l]) << l;
    const unsigned valid = (1u << n) - 1;
    Verdict v;
    v.far = f & valid;
    v.leaf = lf & ~f & valid;
    v.open = ~lf & ~f & valid;
    return v;
  }

 private:
  std::vector<double> lo_[D], hi_[D], ref_[D], open2_;
  std::vector<std::uint32_t> child_, n_child_, leaf_end_;
  std::vector<std::uint8_t> mixed_;
  std::size_t size_ = 0;
};

}  // namespace pik::detail
