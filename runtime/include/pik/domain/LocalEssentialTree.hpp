/// \file LocalEssentialTree.hpp
/// \brief pik::LocalEssentialTree: what each rank must send the others for a long-range walk.
///
/// The local essential tree (Salmon 1991, PhD thesis, Caltech; Warren & Salmon 1993):
/// every rank builds an octree of its own particles with cell moments (the force
/// tree itself, LongRangeTree::buildTreeAndMoments) and, for each other rank r,
/// walks it against the bounding box B_r of r's particles with the same opening
/// criterion as the force walk (TreeParams theta and opening). A cell far enough
/// from all of B_r goes to r as one super-particle (its moments) together with the
/// cell's bounding box; a leaf that must be opened goes as its particles. A cell
/// accepted for B_r is accepted for every i-group inside B_r, so rank r's walk over
/// its own particles plus the imports sees everything the single-process walk
/// needs, at the same accuracy (the cells chosen differ, so forces agree to the
/// tree's approximation error, and to rounding at theta = 0).
///
/// The receiver adds the imports to its pik::LongRangeTree through
/// setImportedParticles and setImportedSuperParticles(spj, extents): the extents
/// make its cells as large as the mass they hold, so its own opening criterion stays
/// as strict as one process's and the error does not grow with the rank count.
/// Positions of the open root domain only (long-range forces in periodic boxes need
/// Ewald sums, which this tree does not compute).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "pik/Box.hpp"
#include "pik/Vec.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/tree/Multipole.hpp"
#include "pik/tree/Octree.hpp"
#include "pik/tree/SuperParticle.hpp"
#include "pik/tree/TreeParams.hpp"

namespace pik {

template <class EPJ, class SPJ>
class LocalEssentialTree {
 public:
  static constexpr int dim = dim_of<EPJ>;
  using dvec = Vec<double, dim>;
  using box_type = Box<double, dim>;

  /// Counts of the last exchange on this rank.
  struct Stats {
    std::size_t epj_sent = 0, spj_sent = 0, epj_received = 0, spj_received = 0;
    std::size_t bytes_sent = 0;  ///< payload to other ranks, counts included
  };

  /// Decides what every other rank needs from `tree`, a LongRangeTree whose tree
  /// and moments were built over this rank's particles alone (buildTreeAndMoments,
  /// no imports), and exchanges it. On one rank it only clears the imports and
  /// does not look at `tree`. Collective.
  template <class Tree, class CommT>
  void exchange(const Tree& tree, const CommT& comm) {
    const int nranks = comm.size(), me = comm.rank();
    stats_ = Stats{};
    imported_epj_.clear();
    imported_spj_.clear();
    imported_box_.clear();
    if (nranks == 1) return;
    const TreeParams& params = tree.params();
    const auto& cells = tree.octree().cells();
    const auto moments = tree.cellMoments();
    const auto boxes = tree.cellBoxes();
    const auto epj = tree.sortedEPJ();
    if (epj.size() != tree.numberOfLocalParticles())
      comm.abort("LocalEssentialTree: the tree must hold this rank's particles only (no imports)");
    const std::size_t n = epj.size();
    // The force walk's criterion (LongRangeTree, TreeParams::opening): used whole
    // when the cell's box does not overlap the target box and d^2 > open2.
    open2_.resize(cells.size());
    for (std::size_t c = 0; c < cells.size(); ++c) open2_[c] = params.opening_radius2(boxes[c], moments[c].pos);
    const box_type mine = n > 0 ? boxes[0] : box_type{};
    const auto targets = comm.allgather(mine);

    std::vector<EPJ> epj_out;
    std::vector<Super> spj_out;
    std::vector<std::size_t> epj_counts(static_cast<std::size_t>(nranks), 0),
        spj_counts(static_cast<std::size_t>(nranks), 0);
    for (int r = 0; r < nranks; ++r) {
      const box_type& target = targets[static_cast<std::size_t>(r)];
      if (r == me || n == 0 || target.empty()) continue;
      const std::size_t e0 = epj_out.size(), s0 = spj_out.size();
      select_for(target, params.distance_to_box(), cells, moments, boxes, epj, epj_out, spj_out);
      epj_counts[static_cast<std::size_t>(r)] = epj_out.size() - e0;
      spj_counts[static_cast<std::size_t>(r)] = spj_out.size() - s0;
    }
    const std::size_t bytes0 = comm.stats().bytes_sent;
    imported_epj_ = comm.alltoallv(std::span<const EPJ>(epj_out), std::span<const std::size_t>(epj_counts));
    const auto supers =
        comm.alltoallv(std::span<const Super>(spj_out), std::span<const std::size_t>(spj_counts));
    imported_spj_.resize(supers.size());
    imported_box_.resize(supers.size());
    for (std::size_t k = 0; k < supers.size(); ++k) imported_spj_[k] = supers[k].spj, imported_box_[k] = supers[k].box;
    stats_.epj_sent = epj_out.size();
    stats_.spj_sent = spj_out.size();
    stats_.epj_received = imported_epj_.size();
    stats_.spj_received = imported_spj_.size();
    stats_.bytes_sent = comm.stats().bytes_sent - bytes0 + sizeof(box_type) * std::size_t(nranks - 1);
  }

  /// What arrived in the last exchange (hand these to the tree).
  std::vector<EPJ>& importedParticles() { return imported_epj_; }
  std::vector<SPJ>& importedSuperParticles() { return imported_spj_; }
  /// Bounding box of the sender's cell for each imported super-particle.
  std::vector<box_type>& importedExtents() { return imported_box_; }
  const Stats& stats() const { return stats_; }

 private:
  /// A super-particle and the box of the cell it stands for, sent together.
  struct Super {
    SPJ spj;
    box_type box;
  };

  /// Appends to the send buffers what a rank whose particles lie in `target` needs.
  template <class Cells, class Moments, class Boxes, class Particles>
  void select_for(const box_type& target, bool to_box, const Cells& cells, const Moments& moments,
                  const Boxes& boxes, const Particles& epj, std::vector<EPJ>& epj_out,
                  std::vector<Super>& spj_out) {
    stack_.clear();
    stack_.push_back(0);
    while (!stack_.empty()) {
      const std::uint32_t c = stack_.back();
      stack_.pop_back();
      const auto& cell = cells[c];
      const double d2 = to_box ? target.distance2(boxes[c]) : target.distance2(moments[c].pos);
      if (!boxes[c].overlaps(target) && d2 > open2_[c]) {
        Super s;
        s.spj.setMoments(moments[c]);
        s.box = boxes[c];
        spj_out.push_back(s);
      } else if (cell.leaf()) {
        epj_out.insert(epj_out.end(), epj.begin() + cell.kind_begin[0], epj.begin() + cell.kind_end[0]);
      } else {
        for (std::uint32_t k = cell.n_child; k-- > 0;) stack_.push_back(cell.child + k);
      }
    }
  }

  std::vector<double> open2_;
  std::vector<std::uint32_t> stack_;
  std::vector<EPJ> imported_epj_;
  std::vector<SPJ> imported_spj_;
  std::vector<box_type> imported_box_;
  Stats stats_;
};

}  // namespace pik
