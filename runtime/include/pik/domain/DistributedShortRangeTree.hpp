/// \file DistributedShortRangeTree.hpp
/// \brief pik::DistributedShortRangeTree: neighbour search over particles spread over ranks.
///
/// A pik::ShortRangeTree plus a pik::ShortRangeHalo: each call sends every other
/// rank the particles within the search radius of its particles (periodic images
/// included), adds what arrives to the tree as imported j-particles, walks, calls
/// the kernel and writes back. Neighbour sets on every rank equal the
/// single-process ones exactly; sums over them agree to rounding (the kernel sees
/// the same pairs, in another order). The seconds of this rank's force work are
/// kept as cost() for the next DomainInfo::decompose.
///
/// ```cpp
/// pik::DomainInfo<double, 3> dinfo(comm);
/// dinfo.set_root_domain(boundary);                 // the same box as the tree's
/// pik::DistributedShortRangeTree<Density, EPI, EPJ, pik::SearchMode::gather> tree({}, boundary);
/// for (step ...) {
///   dinfo.decompose(ps.vector(), tree.cost());
///   pik::exchange_particles(ps, dinfo);            // also wraps into the periodic box
///   tree.calcForceAllAndWriteBack(kernel, ps, comm);
/// }
/// ```
/// Interaction lists are rebuilt every call (ListMode::rebuild): reusing them
/// would need the same halo particles resent with new positions.
#pragma once

#include <utility>

#include "pik/Boundary.hpp"
#include "pik/domain/ShortRangeHalo.hpp"
#include "pik/walk/ShortRangeTree.hpp"

namespace pik {

template <class Force, class EPI, class EPJ, SearchMode Mode>
class DistributedShortRangeTree {
 public:
  using tree_type = ShortRangeTree<Force, EPI, EPJ, Mode>;
  using halo_type = ShortRangeHalo<EPI, EPJ, Mode>;
  static constexpr int dim = tree_type::dim;

  explicit DistributedShortRangeTree(TreeParams p = {}, Boundary<dim> b = Boundary<dim>::open())
      : tree_(p, b) {}

  /// Exchange the halo, then the single-process one call on local particles plus
  /// imports. Collective over `comm`.
  template <class FP, class K, class CommT>
  void calcForceAllAndWriteBack(K&& kernel, ParticleSystem<FP>& ps, const CommT& comm) {
    calcForceAll(kernel, ps, comm);
    tree_.write_back(ps, tree_.profile());
  }

  /// Everything but the write-back: results stay in tree().sortedForce().
  template <class FP, class K, class CommT>
  void calcForceAll(K&& kernel, const ParticleSystem<FP>& ps, const CommT& comm) {
    const double t0 = CommT::wtime();
    exchange(ps, comm);
    const double t1 = CommT::wtime();
    tree_.calcForceAll(kernel, ps);
    cost_ = CommT::wtime() - t1;
    halo_seconds_ = t1 - t0;
  }

  /// Exchange the halo and build the tree, for neighbour queries
  /// (tree().getNeighborList, neighbourIndices) without a kernel. Collective.
  template <class FP, class CommT>
  void build(const ParticleSystem<FP>& ps, const CommT& comm) {
    exchange(ps, comm);
    tree_.build(ps);
  }

  /// Seconds of this rank's force work in the last call (tree, walk, kernel; not
  /// the halo exchange, whose time includes waiting for other ranks).
  double cost() const { return cost_ > 0 ? cost_ : -1.0; }
  double haloSeconds() const { return halo_seconds_; }
  const typename halo_type::Stats& haloStats() const { return halo_.stats(); }
  tree_type& tree() { return tree_; }
  const tree_type& tree() const { return tree_; }
  TreeParams& params() { return tree_.params(); }

 private:
  template <class FP, class CommT>
  void exchange(const ParticleSystem<FP>& ps, const CommT& comm) {
    halo_.exchange(ps, comm, tree_.boundary());
    tree_.setImportedParticles(std::move(halo_.importedParticles()));
  }

  tree_type tree_;
  halo_type halo_;
  double cost_ = -1.0, halo_seconds_ = 0;
};

}  // namespace pik
