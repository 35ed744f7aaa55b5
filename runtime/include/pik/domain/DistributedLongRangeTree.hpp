/// \file DistributedLongRangeTree.hpp
/// \brief pik::DistributedLongRangeTree: the long-range force of particles spread over ranks.
///
/// A pik::LongRangeTree plus a pik::LocalEssentialTree: each call builds the tree
/// over the local particles once, cuts and exchanges the local essential trees from
/// it, puts the imports into a small tree of their own (the local tree is not
/// rebuilt), walks both for every i-group, calls the kernels and writes back, as
/// FDPS's calcForceAllAndWriteBack does with a DomainInfo. The seconds spent on this
/// rank's force work are kept as cost() for the next DomainInfo::decompose, so slow
/// ranks get fewer particles.
///
/// ```cpp
/// pik::DomainInfo<double, 3> dinfo(comm);
/// pik::DistributedLongRangeTree<Force, EPI, EPJ> tree({.theta = 0.5});
/// for (step ...) {
///   dinfo.decompose(ps, tree.cost());
///   pik::exchange_particles(ps, dinfo);
///   tree.calcForceAllAndWriteBack(kernel, kernel_sp, ps, comm);
///   ... kick, drift ...
/// }
/// ```
#pragma once

#include <utility>

#include "pik/domain/LocalEssentialTree.hpp"
#include "pik/walk/LongRangeTree.hpp"

namespace pik {

template <class Force, class EPI, class EPJ, class SPJ = detail::default_spj<EPJ>>
class DistributedLongRangeTree {
 public:
  using tree_type = LongRangeTree<Force, EPI, EPJ, SPJ>;
  using let_type = LocalEssentialTree<EPJ, SPJ>;

  explicit DistributedLongRangeTree(TreeParams p = {}) : tree_(p) {}

  /// Exchange the local essential trees, then the single-process one call on local
  /// particles plus imports. `ps` is a pik::ParticleSystem or a pik::Species bundle.
  /// Collective over `comm`.
  template <class PS, class K, class KS, class CommT>
    requires ParticleSource<PS>
  void calcForceAllAndWriteBack(K&& kernel, KS&& kernel_sp, PS&& ps, const CommT& comm) {
    const double t0 = CommT::wtime();
    tree_.clearImported();
    if (comm.size() == 1) {
      let_.exchange(tree_, comm);  // clears the stats; looks at nothing on one rank
      tree_.calcForceAllAndWriteBack(kernel, kernel_sp, ps);
      cost_ = CommT::wtime() - t0;
      let_seconds_ = 0;
      return;
    }
    // One tree over the local particles: the LET is cut from it, and it is the tree
    // walked (the imports join as a second, small tree).
    tree_.buildTreeAndMoments(ps);
    const double t1 = CommT::wtime();
    let_.exchange(tree_, comm);
    const double t2 = CommT::wtime();
    tree_.setImportedParticles(std::move(let_.importedParticles()));
    tree_.setImportedSuperParticles(std::move(let_.importedSuperParticles()),
                                    std::move(let_.importedExtents()));
    tree_.calcForceWithImportsAndWriteBack(kernel, kernel_sp, ps);
    const double t3 = CommT::wtime();
    let_seconds_ = t2 - t1;
    cost_ = (t1 - t0) + (t3 - t2);
  }

  /// Seconds of this rank's force work in the last call (tree, walk, kernels; not
  /// the exchange, whose time includes waiting for other ranks).
  double cost() const { return cost_ > 0 ? cost_ : -1.0; }
  /// Seconds of the last local-essential-tree cut and exchange (including waiting;
  /// not the tree build, which is part of cost()).
  double letSeconds() const { return let_seconds_; }
  const typename let_type::Stats& letStats() const { return let_.stats(); }
  tree_type& tree() { return tree_; }
  const tree_type& tree() const { return tree_; }
  TreeParams& params() { return tree_.params(); }

 private:
  tree_type tree_;
  let_type let_;
  double cost_ = -1.0, let_seconds_ = 0;
};

}  // namespace pik
