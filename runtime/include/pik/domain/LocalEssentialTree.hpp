/// \file LocalEssentialTree.hpp
/// \brief pik::LocalEssentialTree: what each rank must send the others for a long-range walk.
///
/// The local essential tree (Salmon 1991, PhD thesis, Caltech; Warren & Salmon 1993):
/// every rank builds an octree of its own particles with cell moments and, for each
/// other rank r, walks it against the bounding box B_r of r's particles with the
/// same opening criterion as the force walk (TreeParams theta and opening). A cell far enough from all of B_r goes
/// to r as one super-particle (its moments); a leaf that must be opened goes as its
/// particles. A cell accepted for B_r is accepted for every i-group inside B_r, so
/// rank r's walk over its own particles plus the imports sees everything the
/// single-process walk needs, at the same accuracy (the cells chosen differ, so
/// forces agree to the tree's approximation error, and to rounding at theta = 0).
///
/// The imports go into pik::LongRangeTree through setImportedParticles /
/// setImportedSuperParticles. Positions of the open root domain only (long-range
/// forces in periodic boxes need Ewald sums, which this tree does not compute).
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
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

  /// Builds this rank's tree of `particles` (full particles, converted with
  /// EPJ::copyFromFP), decides what every other rank needs under `params.theta`
  /// and exchanges it. Collective.
  template <class Particles, class CommT>
  void exchange(const Particles& particles, const CommT& comm, const TreeParams& params) {
    static_assert(CopiesFromFP<EPJ, std::remove_cvref_t<decltype(particles[0])>>,
                  "pik: the EPJ type needs `copyFromFP(const FP&)`");
    params.check();
    const int nranks = comm.size(), me = comm.rank();
    stats_ = Stats{};
    imported_epj_.clear();
    imported_spj_.clear();
    if (nranks == 1) return;  // nothing to send: skip building the local tree
    const std::size_t n = particles.size();
    build_local(particles, n, params);
    box_type mine;
    for (const dvec& p : pos_) mine.extend(p);
    const auto boxes = comm.allgather(mine);

    std::vector<EPJ> epj_out;
    std::vector<SPJ> spj_out;
    std::vector<std::size_t> epj_counts(static_cast<std::size_t>(nranks), 0),
        spj_counts(static_cast<std::size_t>(nranks), 0);
    for (int r = 0; r < nranks; ++r) {
      if (r == me || n == 0 || boxes[static_cast<std::size_t>(r)].empty()) continue;
      const std::size_t e0 = epj_out.size(), s0 = spj_out.size();
      select_for(boxes[static_cast<std::size_t>(r)], epj_out, spj_out);
      epj_counts[static_cast<std::size_t>(r)] = epj_out.size() - e0;
      spj_counts[static_cast<std::size_t>(r)] = spj_out.size() - s0;
    }
    const std::size_t bytes0 = comm.stats().bytes_sent;
    imported_epj_ = comm.alltoallv(std::span<const EPJ>(epj_out), std::span<const std::size_t>(epj_counts));
    imported_spj_ = comm.alltoallv(std::span<const SPJ>(spj_out), std::span<const std::size_t>(spj_counts));
    stats_.epj_sent = epj_out.size();
    stats_.spj_sent = spj_out.size();
    stats_.epj_received = imported_epj_.size();
    stats_.spj_received = imported_spj_.size();
    stats_.bytes_sent = comm.stats().bytes_sent - bytes0 + sizeof(box_type) * std::size_t(nranks - 1);
  }

  /// What arrived in the last exchange (hand these to the tree).
  std::vector<EPJ>& importedParticles() { return imported_epj_; }
  std::vector<SPJ>& importedSuperParticles() { return imported_spj_; }
  const Stats& stats() const { return stats_; }

 private:
  template <class Particles>
  void build_local(const Particles& particles, std::size_t n, const TreeParams& params) {
    epj_.resize(n);
    pos_.resize(n);
    for (std::size_t i = 0; i < n; ++i) {
      epj_[i].copyFromFP(particles[i]);
      const auto x = epj_[i].getPos();
      if constexpr (dim == 2) pos_[i] = {double(x.x), double(x.y)};
      else pos_[i] = {double(x.x), double(x.y), double(x.z)};
    }
    cells_.clear();
    opening_ = params.opening;
    if (n == 0) return;
    tree_.build(pos_, {}, params.n_leaf_limit);
    const auto& order = tree_.order();
    sorted_.resize(n);
    for (std::size_t k = 0; k < n; ++k) sorted_[k] = epj_[order[k]];
    // Moments bottom-up: cells are breadth first, so children follow parents.
    const auto& cells = tree_.cells();
    const std::size_t nc = cells.size();
    moments_.assign(nc, Multipole<dim>{});
    cells_.resize(nc);
    for (std::size_t c = nc; c-- > 0;) {
      const auto& cell = cells[c];
      Multipole<dim> m;
      box_type box;
      dvec sum{};
      if (cell.leaf()) {
        for (std::uint32_t k = cell.begin; k < cell.end; ++k) {
          const dvec x = pos_[order[k]];
          const double mk = double(sorted_[k].getCharge());
          m.mass += mk;
          sum += x * mk;
          box.extend(x);
        }
        m.pos = m.mass > 0 ? sum / m.mass : box.center();
        if constexpr (SPJ::order >= 2)
          for (std::uint32_t k = cell.begin; k < cell.end; ++k)
            m.add_quadrupole_of_point(double(sorted_[k].getCharge()), pos_[order[k]]);
      } else {
        for (std::uint32_t k = cell.child; k < cell.child + cell.n_child; ++k) {
          m.mass += moments_[k].mass;
          sum += moments_[k].pos * moments_[k].mass;
          box.extend(cells_[k].box);
        }
        m.pos = m.mass > 0 ? sum / m.mass : box.center();
        if constexpr (SPJ::order >= 2)
          for (std::uint32_t k = cell.child; k < cell.child + cell.n_child; ++k)
            m.add_quadrupole_of(moments_[k]);
      }
      moments_[c] = m;
      const double s = box.max_side();
      cells_[c].box = box;
      // The force walk's criterion (LongRangeTree): used whole when the cell's box
      // does not overlap the target box and s < theta * d, d measured to the cell's
      // box or centre of mass as TreeParams::opening says.
      cells_[c].open2 = params.theta > 0 ? (s / params.theta) * (s / params.theta)
                                         : std::numeric_limits<double>::infinity();
    }
  }

  /// Appends to the send buffers what a rank whose particles lie in `target` needs.
  void select_for(const box_type& target, std::vector<EPJ>& epj_out, std::vector<SPJ>& spj_out) {
    const auto& cells = tree_.cells();
    stack_.clear();
    stack_.push_back(0);
    while (!stack_.empty()) {
      const std::uint32_t c = stack_.back();
      stack_.pop_back();
      const auto& cell = cells[c];
      const LetCell& w = cells_[c];
      const double d2 = opening_ == Opening::box ? target.distance2(w.box)
                                                 : target.distance2(moments_[c].pos);
      if (!w.box.overlaps(target) && d2 > w.open2) {
        SPJ s;
        s.setMoments(moments_[c]);
        spj_out.push_back(s);
      } else if (cell.leaf()) {
        epj_out.insert(epj_out.end(), sorted_.begin() + cell.begin, sorted_.begin() + cell.end);
      } else {
        for (std::uint32_t k = cell.n_child; k-- > 0;) stack_.push_back(cell.child + k);
      }
    }
  }

  struct LetCell {
    box_type box;
    double open2 = 0;
  };

  Octree<dim> tree_;
  std::vector<EPJ> epj_, sorted_;
  std::vector<dvec> pos_;
  std::vector<Multipole<dim>> moments_;
  std::vector<LetCell> cells_;
  std::vector<std::uint32_t> stack_;
  Opening opening_ = Opening::box;
  std::vector<EPJ> imported_epj_;
  std::vector<SPJ> imported_spj_;
  Stats stats_;
};

}  // namespace pik
