/// \file ShortRangeHalo.hpp
/// \brief pik::ShortRangeHalo: the j-particles each rank must send the others for a
///        neighbour search (gather, scatter or symmetric radii; open or periodic).
///
/// Rank r needs every j-particle of another rank that is a neighbour of one of r's
/// i-particles under some periodic image:
///
///   - gather    (|x_i - x_j| < r_i): x_j (an image of it) lies in r's *outer box*,
///                the union of the boxes [x_i - r_i, x_i + r_i] of r's particles;
///   - scatter   (|x_i - x_j| < r_j): x_j (an image) lies within r_j of r's *inner
///                box*, the bounding box of r's particles;
///   - symmetric (|x_i - x_j| < max(r_i, r_j)): either of the two.
///
/// Every rank allgathers its two boxes, then tests each of its particles against
/// each other rank's boxes (after a cheap test of its whole bounding box) and sends
/// the particles that pass in one all-to-all. A particle is sent at most once to a
/// rank, at its own (wrapped) position: the receiver's ShortRangeTree, periodic like
/// the sender's, visits every image of it, exactly as the single-process tree visits
/// every image of every particle. The tests are padded (relative 1e-6 of the radius
/// plus a few ulps of the coordinates), so a pair that the kernel's own cut accepts
/// in single or mixed precision is never lost; the extra particles this admits are
/// rejected by the kernel's cut on every rank alike. Neighbour sets, and so
/// neighbour counts, on every rank then equal the single-process ones exactly.
///
/// Cost: O(N_local × ranks whose boxes come near) tests per exchange and one dense
/// all-to-all (see docs/parallel.md for what this means at 10⁴ ranks).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <type_traits>
#include <vector>

#include "pik/Boundary.hpp"
#include "pik/Box.hpp"
#include "pik/Vec.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/walk/SearchMode.hpp"

namespace pik {

template <class EPI, class EPJ, SearchMode Mode>
class ShortRangeHalo {
 public:
  static constexpr int dim = dim_of<EPJ>;
  static_assert(dim_of<EPI> == dim, "pik: EPI and EPJ dimensions differ");
  static constexpr bool uses_ri = Mode != SearchMode::scatter;
  static constexpr bool uses_rj = Mode != SearchMode::gather;
  using dvec = Vec<double, dim>;
  using box_type = Box<double, dim>;

  /// Counts of the last exchange on this rank.
  struct Stats {
    std::size_t sent = 0, received = 0;
    std::size_t ranks_sent_to = 0;  ///< other ranks that got at least one particle
    std::size_t bytes_sent = 0;     ///< payload to other ranks, counts and boxes included
  };

  /// Decides what every other rank needs from `particles` (full particles, seen
  /// through EPI::copyFromFP for their i-role and EPJ::copyFromFP for their
  /// j-role) and exchanges it. `boundary` must be the one the receiving trees use.
  /// Collective.
  template <class Particles, class CommT>
  void exchange(const Particles& particles, const CommT& comm, const Boundary<dim>& boundary) {
    using FP = std::remove_cvref_t<decltype(particles[0])>;
    static_assert(CopiesFromFP<EPI, FP>, "pik: the EPI type needs `copyFromFP(const FP&)`");
    static_assert(CopiesFromFP<EPJ, FP>, "pik: the EPJ type needs `copyFromFP(const FP&)`");
    const int nranks = comm.size(), me = comm.rank();
    stats_ = Stats{};
    imported_.clear();
    if (nranks == 1) return;  // the local periodic tree already sees every image
    boundary_ = boundary;
    const std::size_t n = particles.size();
    epj_.resize(n);
    xj_.resize(n);
    rj_.assign(n, 0.0);
    Region mine;
    double rj_max = 0;
    box_type jbox;
    for (std::size_t k = 0; k < n; ++k) {
      EPI ei;
      ei.copyFromFP(particles[k]);
      const dvec xi = to_dvec(ei.getPos());
      mine.inner.extend(xi);
      double ri = 0;
      if constexpr (uses_ri) ri = double(ei.getRSearch());
      mine.outer.extend(box_type{xi, xi}.grown(ri));
      mine.ri_max = std::max(mine.ri_max, ri);
      epj_[k].copyFromFP(particles[k]);
      xj_[k] = to_dvec(epj_[k].getPos());
      jbox.extend(xj_[k]);
      if constexpr (uses_rj) rj_[k] = double(epj_[k].getRSearch()), rj_max = std::max(rj_max, rj_[k]);
    }
    const auto regions = comm.allgather(mine);
    // Coordinate scale for the rounding pad: the largest magnitude any rank holds.
    double scale = 0;
    for (const Region& g : regions)
      if (!g.inner.empty())
        for (int d = 0; d < dim; ++d)
          scale = std::max({scale, std::abs(g.outer.lo[d]), std::abs(g.outer.hi[d])});
    abs_pad_ = 16 * eps * scale;

    std::vector<EPJ> out;
    std::vector<std::size_t> counts(static_cast<std::size_t>(nranks), 0);
    for (int r = 0; r < nranks; ++r) {
      const Region& g = regions[static_cast<std::size_t>(r)];
      if (r == me || n == 0 || g.inner.empty() || !near(jbox, rj_max, g)) continue;
      const std::size_t before = out.size();
      for (std::size_t k = 0; k < n; ++k)
        if (needed(xj_[k], rj_[k], g)) out.push_back(epj_[k]);
      counts[static_cast<std::size_t>(r)] = out.size() - before;
      stats_.ranks_sent_to += out.size() > before;
    }
    const std::size_t bytes0 = comm.stats().bytes_sent;
    imported_ = comm.alltoallv(std::span<const EPJ>(out), std::span<const std::size_t>(counts));
    stats_.sent = out.size();
    stats_.received = imported_.size();
    stats_.bytes_sent = comm.stats().bytes_sent - bytes0 + sizeof(Region) * std::size_t(nranks - 1);
  }

  /// What arrived in the last exchange (hand it to ShortRangeTree::setImportedParticles).
  std::vector<EPJ>& importedParticles() { return imported_; }
  const Stats& stats() const { return stats_; }

 private:
  /// What a rank tells the others about its i-particles.
  struct Region {
    box_type inner;  ///< bounding box of the positions
    box_type outer;  ///< union of [x_i - r_i, x_i + r_i] (gather, symmetric)
    double ri_max = 0;
  };

  using real_i = typename pos_type_of<EPI>::value_type;
  using real_j = typename pos_type_of<EPJ>::value_type;
  static constexpr double eps = std::max(double(std::numeric_limits<real_i>::epsilon()),
                                         double(std::numeric_limits<real_j>::epsilon()));

  template <class V>
  static dvec to_dvec(const V& v) {
    if constexpr (dim == 2) return {double(v.x), double(v.y)};
    else return {double(v.x), double(v.y), double(v.z)};
  }

  double pad(double r) const { return 1e-6 * r + abs_pad_; }

  /// How far x lies outside [lo, hi] along d, minimised over periodic images.
  double excess(double x, double lo, double hi, int d) const {
    if (boundary_.periodic[d]) {
      const double L = boundary_.period(d);
      if (hi - lo >= L) return 0;
      const double y = x - L * std::floor((x - lo) / L);  // the image in [lo, lo + L)
      if (y <= hi) return 0;
      return std::max(0.0, std::min(y - hi, lo + L - y));
    }
    return std::max({0.0, lo - x, x - hi});
  }
  /// Squared distance from x (nearest image) to box b.
  double distance2(const dvec& x, const box_type& b) const {
    double s = 0;
    for (int d = 0; d < dim; ++d) {
      const double e = excess(x[d], b.lo[d], b.hi[d], d);
      s += e * e;
    }
    return s;
  }
  /// Squared distance between boxes a and b (nearest images): the corner a.lo
  /// against b grown downwards by a's extent.
  double distance2(const box_type& a, const box_type& b) const {
    double s = 0;
    for (int d = 0; d < dim; ++d) {
      const double e = excess(a.lo[d], b.lo[d] - (a.hi[d] - a.lo[d]), b.hi[d], d);
      s += e * e;
    }
    return s;
  }

  /// Can any particle of this rank (box jbox, largest r_j rj_max) be needed by g?
  bool near(const box_type& jbox, double rj_max, const Region& g) const {
    bool hit = false;
    if constexpr (uses_ri) {
      const double p = pad(g.ri_max);
      hit = hit || distance2(jbox, g.outer) <= p * p;
    }
    if constexpr (uses_rj) {
      const double r = rj_max + pad(rj_max);
      hit = hit || distance2(jbox, g.inner) <= r * r;
    }
    return hit;
  }
  /// Is the particle at x with radius rj needed by the rank with region g?
  bool needed(const dvec& x, double rj, const Region& g) const {
    if constexpr (uses_ri) {
      const double p = pad(g.ri_max);
      if (distance2(x, g.outer) <= p * p) return true;
    }
    if constexpr (uses_rj) {
      const double r = rj + pad(rj);
      if (distance2(x, g.inner) <= r * r) return true;
    }
    return false;
  }

  Boundary<dim> boundary_{};
  double abs_pad_ = 0;
  std::vector<EPJ> epj_;
  std::vector<dvec> xj_;
  std::vector<double> rj_;
  std::vector<EPJ> imported_;
  Stats stats_;
};

}  // namespace pik
