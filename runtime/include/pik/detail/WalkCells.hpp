/// \file WalkCells.hpp
/// \brief What the long-range group walk reads of each cell, in blocks of siblings.
///
/// The walk judges the children of an opened cell all at once: for each, is it far
/// enough to be used whole, a leaf, or to be opened? The children of every inner
/// cell are kept together in one block, as structure of arrays over 2^D lanes (box,
/// the point distances are measured to, opening radius, where to go next), so that
/// one vector operation per quantity judges all siblings (8 doubles: one AVX-512
/// register in 3D) and the outcome is three bit masks; and a visit reads one
/// contiguous block instead of scattered cells. Block 0 holds the root alone;
/// block 1 + k the children of the k-th inner cell (in cell order).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <vector>

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "pik/Box.hpp"
#include "pik/Error.hpp"

namespace pik::detail {

template <int D>
class WalkCells {
 public:
  static constexpr int lanes = 1 << D;

  /// Outcome of judging one block: bit l stands for lane l.
  struct Verdict {
    unsigned far = 0;   ///< use whole (super-particle)
    unsigned leaf = 0;  ///< a leaf that is not far: its particles join the list
    unsigned open = 0;  ///< an inner cell that is not far: visit its block
  };

  struct alignas(64) Block {
    /// Distance to the box: a = lo, b = hi. To a point: a = the point (b unused).
    double a[D][lanes], open2[lanes], b[D][lanes];
    /// Inner cell: its children's block. Leaf: first of its local particles.
    std::uint32_t next[lanes];
    std::uint32_t leaf_end[lanes];  ///< leaf: end of its local particles
    std::uint32_t first_cell;       ///< cell index of lane 0 (lanes are consecutive cells)
    std::uint8_t n = 0;             ///< lanes in use
    std::uint8_t leaf = 0;          ///< bit mask of leaves
    std::uint8_t mixed = 0;         ///< leaves that also hold imported items
  };

  /// Lays out the blocks for a tree's cells (Octree<D>::Cell): which lanes are
  /// leaves, their local particles (item kind 0) and whether they hold other kinds
  /// too (`mixed`: the walk then reads the tree's cell for those ranges).
  template <class Cell>
  void layout(const std::vector<Cell>& cells) {
    const std::size_t nc = cells.size();
    slot_.resize(nc);
    std::size_t n_inner = 0;
    for (const Cell& c : cells) n_inner += !c.leaf();
    // Not cleared: set() writes every lane in use, layout the rest of what is read
    // (clearing tens of megabytes each step would cost more than the layout).
    blocks_.resize(nc > 0 ? 1 + n_inner : 0);
    if (nc == 0) return;
    blocks_[0].first_cell = 0;
    blocks_[0].n = 1;
    blocks_[0].leaf = blocks_[0].mixed = 0;
    slot_[0] = 0;
    if (cells[0].leaf()) {
      const Cell& r = cells[0];
      blocks_[0].next[0] = r.kind_begin[0];
      blocks_[0].leaf_end[0] = r.kind_end[0];
      blocks_[0].leaf = 1;
      blocks_[0].mixed = r.count() != r.kind_end[0] - r.kind_begin[0];
    }
    // Blocks in depth-first order (children in key order): every subtree's blocks are
    // one contiguous range, so the blocks a group's walk visits lie close together.
    std::vector<std::uint32_t> todo;
    if (!cells[0].leaf()) todo.push_back(0);
    std::uint32_t b = 1;
    while (!todo.empty()) {
      const std::uint32_t c = todo.back();
      todo.pop_back();
      const Cell& cell = cells[c];
      for (std::uint32_t k = cell.n_child; k-- > 0;)
        if (!cells[cell.child + k].leaf()) todo.push_back(cell.child + k);
      if (cell.n_child > std::uint32_t(lanes)) throw Error("walk: a cell has more than 2^D children");
      Block& blk = blocks_[b];
      blk.first_cell = cell.child;
      blk.n = std::uint8_t(cell.n_child);
      blk.leaf = blk.mixed = 0;
      for (std::uint32_t k = 0; k < cell.n_child; ++k) {
        slot_[cell.child + k] = b * lanes + k;
        const Cell& ch = cells[cell.child + k];
        if (ch.leaf()) {
          // Local particles are item kind 0; any other kind makes the leaf mixed.
          blk.next[k] = ch.kind_begin[0];
          blk.leaf_end[k] = ch.kind_end[0];
          blk.leaf = std::uint8_t(blk.leaf | (1u << k));
          if (ch.count() != ch.kind_end[0] - ch.kind_begin[0]) blk.mixed = std::uint8_t(blk.mixed | (1u << k));
        }
      }
      // This cell's own lane (in its parent's block) points here.
      const std::uint32_t s = slot_[c];
      blocks_[s / lanes].next[s % lanes] = b;
      ++b;
    }
  }

  std::size_t blocks() const { return blocks_.size(); }
  /// Where cell c is judged: block * lanes + lane (siblings are consecutive, blocks in
  /// the walk's depth-first order: arrays indexed so are read nearly in order).
  std::uint32_t slot(std::size_t c) const { return slot_[c]; }

  /// Cell c: tight box, centre of mass, squared opening radius; `to_box` says what
  /// distances are measured to (the cell's box, or its centre of mass).
  ///
  /// No separate test that the boxes are apart is needed. To the box: a distance
  /// above open2 >= 0 means a gap along some axis. To the centre of mass: the box
  /// lies within R of it, R the distance to its farthest corner, so a distance
  /// above R means apart; open2 is raised to at least R^2, which changes nothing
  /// while s / theta >= sqrt(3) s >= R (theta <= 0.577) and opens cells the boxes of
  /// which may touch the group's at larger theta. (Different cells write different
  /// lanes: cells may be set in parallel.)
  void set(std::size_t c, const Box<double, D>& box, const Vec<double, D>& com, double open2, bool to_box) {
    const std::uint32_t s = slot_[c];
    Block& blk = blocks_[s / lanes];
    const int l = int(s % lanes);
    if (to_box) {
      for (int d = 0; d < D; ++d) blk.a[d][l] = box.lo[d], blk.b[d][l] = box.hi[d];
    } else {
      double r2 = 0;
      for (int d = 0; d < D; ++d) {
        const double e = std::max(com[d] - box.lo[d], box.hi[d] - com[d]);
        r2 += e * e;
        blk.a[d][l] = blk.b[d][l] = com[d];
      }
      open2 = box.empty() ? open2 : std::max(open2, r2);
    }
    blk.open2[l] = open2;
  }

  const Block& block(std::uint32_t b) const { return blocks_[b]; }

  /// Judges the lanes of block blk against an i-group's box: a cell is far when the
  /// squared distance from the group's box to the cell's box (to_box) or centre of
  /// mass exceeds open2 (see set()).
  template <bool to_box>
  [[gnu::always_inline]] static inline Verdict judge(const Block& blk, const Box<double, D>& g) {
    const unsigned valid = (1u << blk.n) - 1;
    Verdict v;
#if defined(__AVX512F__)
    if constexpr (D == 3) {
      // The same arithmetic as below, written so that the comparison yields the
      // bit mask directly (compilers rebuild it from a vector of booleans slowly).
      const __m512d zero = _mm512_setzero_pd();
      __m512d d2 = zero;
      for (int d = 0; d < D; ++d) {
        const __m512d a = _mm512_load_pd(blk.a[d]);
        const __m512d b = to_box ? _mm512_load_pd(blk.b[d]) : a;
        const __m512d x = _mm512_sub_pd(_mm512_set1_pd(g.lo[d]), b);
        const __m512d y = _mm512_sub_pd(a, _mm512_set1_pd(g.hi[d]));
        // (maskz_max: plain max_pd trips GCC 12's false -Wuninitialized, PR 105593)
        const __m512d e = _mm512_maskz_max_pd(0xff, _mm512_maskz_max_pd(0xff, y, x), zero);
        d2 = _mm512_fmadd_pd(e, e, d2);
      }
      const unsigned f = _mm512_cmp_pd_mask(d2, _mm512_load_pd(blk.open2), _CMP_GT_OQ);
      v.far = f & valid;
      v.leaf = blk.leaf & ~f & valid;
      v.open = ~unsigned(blk.leaf) & ~f & valid;
      return v;
    }
#endif
    alignas(64) std::int64_t far[lanes];
    for (int l = 0; l < lanes; ++l) {
      double d2 = 0;
      for (int d = 0; d < D; ++d) {
        const double x = g.lo[d] - (to_box ? blk.b[d][l] : blk.a[d][l]);
        const double y = blk.a[d][l] - g.hi[d];
        const double e = std::max(std::max(x, y), 0.0);
        d2 += e * e;
      }
      far[l] = d2 > blk.open2[l];
    }
    unsigned f = 0;
    for (int l = 0; l < lanes; ++l) f |= unsigned(far[l]) << l;
    v.far = f & valid;
    v.leaf = blk.leaf & ~f & valid;
    v.open = ~unsigned(blk.leaf) & ~f & valid;
    return v;
  }

  /// Asks for the cache lines of block b that judge<to_box> reads, ahead of its visit.
  void prefetch(std::uint32_t b, bool to_box) const {
    const char* p = reinterpret_cast<const char*>(&blocks_[b]);
    for (std::size_t o = 0; o < offsetof(Block, b); o += 64) __builtin_prefetch(p + o);
    for (std::size_t o = to_box ? offsetof(Block, b) : offsetof(Block, next); o < sizeof(Block); o += 64)
      __builtin_prefetch(p + o);
  }

 private:
  std::vector<Block> blocks_;
  std::vector<std::uint32_t> slot_;  ///< cell -> block * lanes + lane
};

}  // namespace pik::detail
