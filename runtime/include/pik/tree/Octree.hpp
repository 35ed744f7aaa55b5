/// \file Octree.hpp
/// \brief Pointer-free octree (quadtree in 2D) over radix-sorted Morton keys.
///
/// The octree knows only positions: it sorts items by key, cuts the sorted array into
/// cells top-down (children of a cell are contiguous in the cell array, breadth first,
/// so parents always precede children) and picks i-groups. What the cells carry
/// (multipole moments, search radii) is up to the walks, which fill their own arrays
/// indexed like `cells()`.
///
/// Items are of three kinds, so that a distributed run can add what other ranks send
/// (the local essential tree): local particles (also the i-particles), imported
/// j-particles and imported super-particles. All three are sorted together; each
/// cell records a contiguous range of each kind in the kind's own sorted order.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "pik/Box.hpp"
#include "pik/Error.hpp"
#include "pik/Vec.hpp"
#include "pik/detail/RadixSort.hpp"
#include "pik/detail/Threads.hpp"
#include "pik/tree/IndexRange.hpp"
#include "pik/tree/MortonKey.hpp"

namespace pik {

/// What an item of the tree is.
enum class ItemKind : std::uint8_t {
  local = 0,              ///< a particle of this process: i-particle and j-particle
  imported_particle = 1,  ///< a j-particle received from elsewhere (EPJ)
  imported_super = 2,     ///< a super-particle received from elsewhere (SPJ)
};
inline constexpr int n_item_kinds = 3;

template <int D>
class Octree {
 public:
  using vec = Vec<double, D>;
  static constexpr int n_children = 1 << D;
  /// Cells stop splitting at this depth even if particles are not yet separated (a
  /// safety net; real data is separated long before, or is all at one point).
  static constexpr int max_depth = 4096;

  struct Cell {
    std::uint32_t begin = 0, end = 0;  ///< items [begin, end) in sorted order
    std::uint32_t child = 0;           ///< index of the first child cell
    std::uint16_t n_child = 0;         ///< 0 for a leaf
    std::uint16_t depth = 0;           ///< 0 at the root (saturates at 65535)
    std::uint32_t kind_begin[n_item_kinds] = {}, kind_end[n_item_kinds] = {};

    bool leaf() const { return n_child == 0; }
    std::uint32_t count() const { return end - begin; }
    std::uint32_t count(ItemKind k) const { return kind_end[int(k)] - kind_begin[int(k)]; }
  };

  /// Builds the tree. `kind` may be empty (every item local). Cells with at most
  /// `leaf_limit` items are leaves.
  void build(std::span<const vec> pos, std::span<const ItemKind> kind, int leaf_limit) {
    if (leaf_limit < 1) throw Error("leaf limit must be at least 1, got " + std::to_string(leaf_limit));
    if (pos.size() >= 0xffffffffu) throw Error("more than 2^32-1 items in one tree");
    const std::uint32_t n = std::uint32_t(pos.size());
    cells_.clear();
    frames_.clear();
    depth_in_frame_.clear();
    // Root frame: the bounding cube of all items, in double.
    Box<double, D> box;
    {
      // Per-block boxes on all threads, merged in block order.
      const std::size_t nb = std::max<std::size_t>(1, std::min<std::size_t>(n / 16384, 64));
      std::vector<Box<double, D>> part(nb);
      detail::parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
        for (std::size_t i = n * std::size_t(b) / nb; i < n * (std::size_t(b) + 1) / nb; ++i)
          part[std::size_t(b)].extend(pos[i]);
      });
      for (const auto& pb : part) box.extend(pb);
    }
    KeyFrame<D> root;
    if (n > 0) {
      for (int d = 0; d < D; ++d) root.lo[d] = box.lo[d];
      root.side = box.max_side();
      if (!std::isfinite(root.side))
        throw Error("particle positions span more than the range of double");
      if (root.side == 0) root.side = 1;
    }
    keys_.resize(n);
    // Warm start: items that moved a little since the last build are nearly in its
    // order, so their keys listed in that order need only a short fix-up (see
    // sort_nearly_sorted); the result is the sort of the keys in item order either way.
    const bool warm = order_.size() == n && n >= 4096;
    bool sorted = false;
    if (warm) {
      item_key_.resize(n);
      detail::parallel_for_static(std::ptrdiff_t(n), [&](std::ptrdiff_t i) {
        item_key_[std::size_t(i)] = root.key(pos[std::size_t(i)]);
      });
      detail::parallel_for_static(std::ptrdiff_t(n), [&](std::ptrdiff_t i) {
        const std::uint32_t j = order_[std::size_t(i)];
        keys_[std::size_t(i)] = {item_key_[j], j};
      });
      sorted = detail::sort_nearly_sorted(keys_, scratch_, aside_, n / 8);
      if (!sorted)
        detail::parallel_for_static(std::ptrdiff_t(n), [&](std::ptrdiff_t i) {
          keys_[std::size_t(i)] = {item_key_[std::size_t(i)], std::uint32_t(i)};
        });
    } else {
      detail::parallel_for_static(std::ptrdiff_t(n), [&](std::ptrdiff_t i) {
        keys_[std::size_t(i)] = {root.key(pos[std::size_t(i)]), std::uint32_t(i)};
      });
    }
    if (!sorted) detail::radix_sort(keys_, scratch_);

    cells_.push_back(Cell{0, n, 0, 0, 0, {}, {}});
    frames_.push_back(root);
    depth_in_frame_.push_back(0);
    split_all(pos, std::uint32_t(leaf_limit));

    order_.resize(n);
    detail::parallel_for_static(std::ptrdiff_t(n), [&](std::ptrdiff_t i) { order_[std::size_t(i)] = keys_[std::size_t(i)].index; });
    assign_kind_ranges(kind);
    // The split's per-cell scratch keeps its memory for the next build: freeing it
    // would hand it back to the system, and the next step would pay a page fault per
    // 4 KiB to get it back (several milliseconds at 2^20 particles).
    frames_.clear();
    depth_in_frame_.clear();
  }

  /// Takes another tree's result (cells, order, kind ranges) without its build scratch
  /// (keys, sort buffers, the split's subtrees: several times the result's size). A later
  /// build() of this tree works as after its own build (warm start from the order).
  void assign_result(const Octree& o) {
    cells_ = o.cells_;
    order_ = o.order_;
    for (int k = 0; k < n_item_kinds; ++k) sorted_[k] = o.sorted_[k];
  }

  const std::vector<Cell>& cells() const { return cells_; }
  /// Sorted position -> item index.
  const std::vector<std::uint32_t>& order() const { return order_; }
  /// Sorted items of one kind, as item indices (the arrays that kind ranges index).
  const std::vector<std::uint32_t>& sorted(ItemKind k) const { return sorted_[int(k)]; }

  /// i-groups as ranges of the sorted local particles, in key order. A cell with more
  /// than `group_limit` local particles is split: its children are packed, in order,
  /// into groups of at most `group_limit` particles (so groups stay inside one parent
  /// cell and spatially compact, yet fuller than single cells); children that are too
  /// big are split again. A leaf with more local particles than the limit (particles
  /// at one point) is one group.
  std::vector<IndexRange> groups(int group_limit) const {
    std::vector<IndexRange> out;
    groups(group_limit, out);
    return out;
  }
  /// The same into `out` (its memory is reused).
  void groups(int group_limit, std::vector<IndexRange>& out) const {
    if (group_limit < 1)
      throw Error("group limit must be at least 1, got " + std::to_string(group_limit));
    out.clear();
    if (cells_.empty() || cells_[0].count(ItemKind::local) == 0) return;
    const Cell& root = cells_[0];
    if (root.count(ItemKind::local) <= std::uint32_t(group_limit) || root.leaf()) {
      out.push_back({root.kind_begin[0], root.kind_end[0]});
    } else {
      pack_children(0, std::uint32_t(group_limit), out);
    }
  }

 private:
  /// Packs the children of cell c into groups (recursion depth <= tree depth).
  void pack_children(std::uint32_t c, std::uint32_t lim, std::vector<IndexRange>& out) const {
    const Cell& cell = cells_[c];
    IndexRange pack{0, 0};
    bool open = false;
    for (std::uint32_t k = cell.child; k < cell.child + cell.n_child; ++k) {
      const Cell& ch = cells_[k];
      const std::uint32_t nl = ch.count(ItemKind::local);
      if (nl == 0) continue;
      if (nl > lim && !ch.leaf()) {
        if (open) out.push_back(pack), open = false;
        pack_children(k, lim, out);
      } else if (open && pack.end - pack.begin + nl <= lim) {
        pack.end = ch.kind_end[0];  // local ranges of consecutive children touch
      } else {
        if (open) out.push_back(pack);
        pack = {ch.kind_begin[0], ch.kind_end[0]};
        open = true;
      }
    }
    if (open) out.push_back(pack);
  }

  /// Cells being split, with each cell's key frame and key digits used so far.
  struct Splitting {
    std::vector<Cell>& cells;
    std::vector<KeyFrame<D>>& frames;
    std::vector<int>& depth_in_frame;
  };

  /// Splits the root down to the leaves, breadth first. The top levels are split
  /// here; below them each cell's subtree is split on its own (on all threads, each
  /// into its own breadth-first array), and the subtrees are merged level by level,
  /// so the cell array is the one a serial breadth-first split makes.
  void split_all(std::span<const vec> pos, std::uint32_t leaf_limit) {
    // Below 2^16 items, or on one thread, the serial split is as fast. Otherwise the
    // top levels are split here, level by level, until no cell of the next level (the
    // frontier) holds more than a sixteenth of the items: with a few items far out (the
    // debris of an impact) most of them sit in one cell of the first levels, and a
    // frontier at a fixed depth would leave that cell's subtree to one thread. A frontier
    // of more than `wide` cells ends it too: around one dense clump in a populated volume
    // each further level would split thousands of cells here.
    const bool parallel = pos.size() >= 65536 && detail::max_threads() > 1;
    const std::size_t big = pos.size() / 16, wide = 8192;
    Splitting all{cells_, frames_, depth_in_frame_};
    std::size_t c = 0;
    if (!parallel) {
      for (; c < cells_.size(); ++c) split(all, c, pos, leaf_limit);
      return;
    }
    for (int level = 0;; ++level) {
      for (; c < cells_.size() && cells_[c].depth <= level; ++c) split(all, c, pos, leaf_limit);
      if (c == cells_.size()) break;
      // cells [c, end) are the next level's: split them on the threads unless one is big
      std::uint32_t largest = 0;
      for (std::size_t k = c; k < cells_.size(); ++k) largest = std::max(largest, cells_[k].count());
      if (level >= 1 && (largest <= big || cells_.size() - c > wide || level >= 63)) break;
    }
    const std::size_t f0 = c, nf = cells_.size() - f0;
    if (nf == 0) return;
    // Kept between builds (cleared, not freed: no page faults to get the memory back).
    if (subs_.size() < nf) subs_.resize(nf);
    auto& subs = subs_;
    detail::parallel_for(std::ptrdiff_t(nf), [&](std::ptrdiff_t i, int) {
      Sub& sub = subs[std::size_t(i)];
      sub.cells.clear(), sub.frames.clear(), sub.depth_in_frame.clear(), sub.level.clear();
      sub.cells.push_back(cells_[f0 + std::size_t(i)]);
      sub.frames.push_back(frames_[f0 + std::size_t(i)]);
      sub.depth_in_frame.push_back(depth_in_frame_[f0 + std::size_t(i)]);
      Splitting local{sub.cells, sub.frames, sub.depth_in_frame};
      for (std::size_t k = 0; k < sub.cells.size(); ++k) split(local, k, pos, leaf_limit);
      sub.level.push_back(0);
      for (std::uint32_t k = 1; k < sub.cells.size(); ++k)
        if (sub.cells[k].depth != sub.cells[k - 1].depth) sub.level.push_back(k);
      sub.level.push_back(std::uint32_t(sub.cells.size()));
    });
    // Level r below the frontier: the subtrees' level-r cells, in frontier order.
    std::size_t levels = 0, total = cells_.size();
    for (std::size_t i = 0; i < nf; ++i) {
      const Sub& sub = subs[i];
      levels = std::max(levels, sub.level.size() - 1), total += sub.cells.size() - 1;
    }
    cells_.reserve(total);
    std::vector<std::uint32_t> base(nf * (levels + 1), 0);  // base[i * (levels + 1) + r]
    for (std::size_t r = 1; r < levels; ++r)
      for (std::size_t i = 0; i < nf; ++i) {
        const Sub& sub = subs[i];
        base[i * (levels + 1) + r] = std::uint32_t(cells_.size());
        if (r + 1 < sub.level.size())
          cells_.insert(cells_.end(), sub.cells.begin() + sub.level[r], sub.cells.begin() + sub.level[r + 1]);
      }
    // Child indices from local to global.
    for (std::size_t i = 0; i < nf; ++i) {
      const Sub& sub = subs[i];
      for (std::size_t r = 0; r + 1 < sub.level.size(); ++r)
        for (std::uint32_t k = sub.level[r]; k < sub.level[r + 1]; ++k) {
          const Cell& lc = sub.cells[k];
          Cell& gc = r == 0 ? cells_[f0 + i] : cells_[base[i * (levels + 1) + r] + (k - sub.level[r])];
          gc.n_child = lc.n_child;
          gc.child = lc.leaf() ? 0 : base[i * (levels + 1) + r + 1] + (lc.child - sub.level[r + 1]);
        }
    }
  }

  void split(Splitting& t, std::size_t c, std::span<const vec> pos, std::uint32_t leaf_limit) {
    auto& cells = t.cells;
    auto& frames = t.frames;
    auto& depth_in_frame = t.depth_in_frame;
    const std::uint32_t b = cells[c].begin, e = cells[c].end;
    if (e - b <= leaf_limit || cells[c].depth >= max_depth) return;
    int kd = depth_in_frame[c];
    if (kd == MortonKey<D>::levels) {
      // Keys are used up: particles closer than 2^-21 of the frame. Key them again
      // relative to their own bounding cube, unless they all sit at one point.
      Box<double, D> box;
      for (std::uint32_t i = b; i < e; ++i) box.extend(pos[keys_[i].index]);
      if (box.max_side() == 0) return;
      KeyFrame<D> f;
      for (int d = 0; d < D; ++d) f.lo[d] = box.lo[d];
      f.side = box.max_side();
      for (std::uint32_t i = b; i < e; ++i) keys_[i].key = f.key(pos[keys_[i].index]);
      std::stable_sort(keys_.begin() + b, keys_.begin() + e,
                       [](const detail::KeyIndex& x, const detail::KeyIndex& y) { return x.key < y.key; });
      frames[c] = f;
      kd = 0;
    }
    const KeyFrame<D> frame = frames[c];
    const std::uint16_t depth = cells[c].depth;
    std::uint32_t first_child = std::uint32_t(cells.size()), n_child = 0;
    std::uint32_t start = b;
    for (unsigned digit = 0; digit < unsigned(n_children) && start < e; ++digit) {
      std::uint32_t stop;
      if (e - start <= 32) {
        stop = start;
        while (stop < e && MortonKey<D>::digit(keys_[stop].key, kd) <= digit) ++stop;
      } else {
        auto it = std::partition_point(keys_.begin() + start, keys_.begin() + e,
                                       [&](const detail::KeyIndex& x) {
                                         return MortonKey<D>::digit(x.key, kd) <= digit;
                                       });
        stop = std::uint32_t(it - keys_.begin());
      }
      if (stop > start) {
        Cell child{start, stop, 0, 0, std::uint16_t(depth == 65535 ? depth : depth + 1), {}, {}};
        cells.push_back(child);
        frames.push_back(frame.child(digit));
        depth_in_frame.push_back(kd + 1);
        ++n_child;
      }
      start = stop;
    }
    cells[c].child = first_child;
    cells[c].n_child = std::uint16_t(n_child);
  }

  void assign_kind_ranges(std::span<const ItemKind> kind) {
    const std::uint32_t n = std::uint32_t(order_.size());
    for (auto& s : sorted_) s.clear();
    if (kind.empty()) {
      sorted_[0] = order_;
      detail::parallel_for_static(std::ptrdiff_t(cells_.size()), [&](std::ptrdiff_t k) {
        Cell& c = cells_[std::size_t(k)];
        c.kind_begin[0] = c.begin, c.kind_end[0] = c.end;
      });
      return;
    }
    if (kind.size() != n) throw Error("item kinds and positions differ in length");
    // prefix[k][i]: items of kind k among sorted positions [0, i).
    std::vector<std::uint32_t> prefix[n_item_kinds];
    for (auto& p : prefix) p.assign(n + 1, 0);
    for (std::uint32_t i = 0; i < n; ++i) {
      int k = int(kind[order_[i]]);
      for (int q = 0; q < n_item_kinds; ++q) prefix[q][i + 1] = prefix[q][i] + (q == k);
      sorted_[k].push_back(order_[i]);
    }
    for (Cell& c : cells_)
      for (int q = 0; q < n_item_kinds; ++q)
        c.kind_begin[q] = prefix[q][c.begin], c.kind_end[q] = prefix[q][c.end];
  }

  std::vector<Cell> cells_;
  std::vector<std::uint32_t> order_;
  std::vector<std::uint32_t> sorted_[n_item_kinds];
  std::vector<detail::KeyIndex> keys_, scratch_, aside_;
  std::vector<std::uint64_t> item_key_;  ///< key of each item, in item order (warm start)
  std::vector<KeyFrame<D>> frames_;
  std::vector<int> depth_in_frame_;
  /// The parallel split's per-subtree arrays (split_all).
  struct Sub {
    std::vector<Cell> cells;
    std::vector<KeyFrame<D>> frames;
    std::vector<int> depth_in_frame;
    std::vector<std::uint32_t> level;  ///< first local cell of each level, then the end
  };
  std::vector<Sub> subs_;
};

}  // namespace pik
