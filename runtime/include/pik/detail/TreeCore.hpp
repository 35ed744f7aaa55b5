/// \file TreeCore.hpp
/// \brief What both walks share: loading particles into a sorted tree and writing back.
///
/// The tree keeps its own copies of the i-particles (EPI) and j-particles (EPJ) in
/// key order, so walks read contiguous memory and kernels get plain arrays. Imported
/// EPJ / SPJ (from other ranks) join the same tree as items of their own kind.
#pragma once

#include <algorithm>
#include <cstdint>
#include <sstream>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "pik/Box.hpp"
#include "pik/Error.hpp"
#include "pik/Profiler.hpp"
#include "pik/Vec.hpp"
#include "pik/detail/Threads.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/particle/ParticleSystem.hpp"
#include "pik/particle/Species.hpp"
#include "pik/tree/Octree.hpp"
#include "pik/tree/TreeParams.hpp"

namespace pik::detail {

template <int D, class V>
Vec<double, D> to_dvec(const V& v) {
  if constexpr (D == 2) {
    return {double(v.x), double(v.y)};
  } else {
    return {double(v.x), double(v.y), double(v.z)};
  }
}

template <int D>
std::string describe_position(const char* what, std::size_t i, const Vec<double, D>& p) {
  std::ostringstream os;
  os << what << " " << i << " has a non-finite position " << p;
  return os.str();
}

/// Asks for the cache lines of full particle i ahead of its use (the sorted copies and
/// the write-back visit the particle system in key order, i.e. at random).
/// (A prefetch for writing made the write-back no faster on the machine of
/// docs/bench-tree.md.)
template <class FP>
inline void prefetch_particle(const ParticleSystem<FP>& ps, std::size_t i) {
  const char* p = reinterpret_cast<const char*>(&ps[i]);
  __builtin_prefetch(p);
  if constexpr (sizeof(FP) > 64) __builtin_prefetch(p + sizeof(FP) - 1);
}
template <class PS>
  requires(!is_particle_system<std::remove_cvref_t<PS>>::value)
inline void prefetch_particle(const PS&, std::size_t) {}
/// How far ahead (in particles) the key-order loops ask for particles.
inline constexpr std::size_t prefetch_distance = 16;

/// Sorted EPI / EPJ copies, the octree over them, the permutation back to the
/// particle system, and the sorted results.
template <class EPI, class EPJ, class Force, class SPJ, int D>
class TreeCore {
 public:
  using dvec = Vec<double, D>;

  template <class FP>
  struct epi_copies : std::bool_constant<CopiesFromFP<EPI, FP>> {};
  template <class FP>
  struct epj_copies : std::bool_constant<CopiesFromFP<EPJ, FP>> {};
  template <class FP>
  struct takes_force : std::bool_constant<TakesForce<FP, Force>> {};

  /// Loads the particle system (or pik::Species bundle) and any imported particles,
  /// builds the octree.
  template <ParticleSource PS>
  void load_and_build(const PS& ps, const TreeParams& params, Profiler& prof) {
    static_assert(all_particles<epi_copies, PS>::value,
                  "pik: the EPI type needs `copyFromFP(const FP&)` (for every species' FP)");
    static_assert(all_particles<epj_copies, PS>::value,
                  "pik: the EPJ type needs `copyFromFP(const FP&)` (for every species' FP)");
    params.check();
    auto t = prof.scope("tree build");
    n_local_ = ps.size();
    const std::size_t ne = imported_epj_.size(), ns = imported_spj_.size();
    const std::size_t n = n_local_ + ne + ns;
    pos_.resize(n);
    kind_.clear();
    // Converted and checked on all threads; the first bad particle is then named.
    std::vector<unsigned char> bad(max_threads(), 0);
    parallel_for_static(std::ptrdiff_t(n_local_), [&](std::ptrdiff_t i) {
      visit_particle(ps, std::size_t(i), [&](const auto& p) { pos_[i] = to_dvec<D>(p.getPos()); });
      if (!isfinite(pos_[i])) bad[std::size_t(thread_num())] = 1;
    });
    if (std::find(bad.begin(), bad.end(), 1) != bad.end())
      for (std::size_t i = 0; i < n_local_; ++i)
        if (!isfinite(pos_[i])) throw Error(ps.describe_bad_position(i));
    for (std::size_t i = 0; i < ne; ++i) {
      pos_[n_local_ + i] = to_dvec<D>(imported_epj_[i].getPos());
      if (!isfinite(pos_[n_local_ + i]))
        throw Error(describe_position<D>("imported particle", i, pos_[n_local_ + i]));
    }
    if constexpr (!std::is_void_v<SPJ>) {
      for (std::size_t i = 0; i < ns; ++i) {
        pos_[n_local_ + ne + i] = to_dvec<D>(imported_spj_[i].getPos());
        if (!isfinite(pos_[n_local_ + ne + i]))
          throw Error(describe_position<D>("imported super-particle", i, pos_[n_local_ + ne + i]));
      }
    }
    if (ne + ns > 0) {
      kind_.assign(n, ItemKind::local);
      for (std::size_t i = 0; i < ne; ++i) kind_[n_local_ + i] = ItemKind::imported_particle;
      for (std::size_t i = 0; i < ns; ++i) kind_[n_local_ + ne + i] = ItemKind::imported_super;
    }
    tree_.build(pos_, kind_, params.n_leaf_limit);
    tree_.groups(params.n_group_limit, groups_);
    // Sorted copies. EPJ: local particles first, then imported ones, each in key order.
    const auto& loc = tree_.sorted(ItemKind::local);
    epi_.resize(n_local_);
    epj_.resize(n_local_ + ne);
    const std::size_t nl = n_local_;
    parallel_for_static(std::ptrdiff_t(n_local_), [&](std::ptrdiff_t i) {
      if (std::size_t(i) + prefetch_distance < nl) prefetch_particle(ps, loc[std::size_t(i) + prefetch_distance]);
      visit_particle(ps, loc[i], [&](const auto& fp) {
        epi_[i].copyFromFP(fp);
        epj_[i].copyFromFP(fp);
      });
    });
    const auto& imp = tree_.sorted(ItemKind::imported_particle);
    for (std::size_t i = 0; i < imp.size(); ++i) epj_[n_local_ + i] = imported_epj_[imp[i] - n_local_];
    if constexpr (!std::is_void_v<SPJ>) {
      const auto& sup = tree_.sorted(ItemKind::imported_super);
      spj_imported_sorted_.resize(sup.size());
      for (std::size_t i = 0; i < sup.size(); ++i)
        spj_imported_sorted_[i] = imported_spj_[sup[i] - n_local_ - ne];
      // Extents of the imported super-particles (when given), in the same order.
      spj_box_imported_sorted_.resize(imported_spj_box_.size() == ns ? sup.size() : 0);
      for (std::size_t i = 0; i < spj_box_imported_sorted_.size(); ++i)
        spj_box_imported_sorted_[i] = imported_spj_box_[sup[i] - n_local_ - ne];
    }
    force_.resize(n_local_);
  }

  /// After a load_and_build without imports: puts the imported particles and
  /// super-particles into a second tree of their own (`import_tree()`; imported
  /// particles are its item kind 0, super-particles kind 2) instead of rebuilding the
  /// local one. sortedEPJ() becomes local particles then imported ones in the import
  /// tree's order; the imported super-particles are sorted in that tree's order too.
  void load_imports_apart(const TreeParams& params, Profiler& prof) {
    auto t = prof.scope("tree build");
    if (epj_.size() != n_local_)
      throw Error("load_imports_apart: the local tree was built with imports in it");
    const std::size_t ne = imported_epj_.size(), ns = imported_spj_.size();
    ipos_.resize(ne + ns);
    ikind_.assign(ne + ns, ItemKind::local);
    for (std::size_t i = 0; i < ne; ++i) {
      ipos_[i] = to_dvec<D>(imported_epj_[i].getPos());
      if (!isfinite(ipos_[i])) throw Error(describe_position<D>("imported particle", i, ipos_[i]));
    }
    if constexpr (!std::is_void_v<SPJ>) {
      for (std::size_t i = 0; i < ns; ++i) {
        ipos_[ne + i] = to_dvec<D>(imported_spj_[i].getPos());
        if (!isfinite(ipos_[ne + i])) throw Error(describe_position<D>("imported super-particle", i, ipos_[ne + i]));
        ikind_[ne + i] = ItemKind::imported_super;
      }
    }
    itree_.build(ipos_, ikind_, params.n_leaf_limit);
    const auto& imp = itree_.sorted(ItemKind::local);
    epj_.resize(n_local_ + imp.size());
    for (std::size_t i = 0; i < imp.size(); ++i) epj_[n_local_ + i] = imported_epj_[imp[i]];
    if constexpr (!std::is_void_v<SPJ>) {
      const auto& sup = itree_.sorted(ItemKind::imported_super);
      spj_imported_sorted_.resize(sup.size());
      for (std::size_t i = 0; i < sup.size(); ++i) spj_imported_sorted_[i] = imported_spj_[sup[i] - ne];
      spj_box_imported_sorted_.resize(imported_spj_box_.size() == ns ? sup.size() : 0);
      for (std::size_t i = 0; i < spj_box_imported_sorted_.size(); ++i)
        spj_box_imported_sorted_[i] = imported_spj_box_[sup[i] - ne];
    }
  }

  /// Reuse: same particles in the same order, new contents (positions may have moved
  /// a little; the tree topology is kept).
  template <ParticleSource PS>
  void reload(const PS& ps, Profiler& prof) {
    auto t = prof.scope("tree build");
    if (ps.size() != n_local_)
      throw Error("interaction-list reuse needs the same particles as when the list was made (had " +
                  std::to_string(n_local_) + ", now " + std::to_string(ps.size()) + ")");
    ps.checkPositions();
    const auto& loc = tree_.sorted(ItemKind::local);
    const std::size_t nl = n_local_;
    parallel_for_static(std::ptrdiff_t(n_local_), [&](std::ptrdiff_t i) {
      if (std::size_t(i) + prefetch_distance < nl) prefetch_particle(ps, loc[std::size_t(i) + prefetch_distance]);
      visit_particle(ps, loc[i], [&](const auto& fp) {
        epi_[i].copyFromFP(fp);
        epj_[i].copyFromFP(fp);
      });
    });
  }

  template <ParticleSource PS>
  void write_back(PS& ps, Profiler& prof) const {
    static_assert(all_particles<takes_force, std::remove_const_t<PS>>::value,
                  "pik: the full particle type needs `copyFromForce(const FORCE&)` (every species)");
    auto t = prof.scope("write back");
    const auto& loc = tree_.sorted(ItemKind::local);
    const std::size_t nl = n_local_;
    parallel_for_static(std::ptrdiff_t(n_local_), [&](std::ptrdiff_t i) {
      if (std::size_t(i) + prefetch_distance < nl) prefetch_particle(ps, loc[std::size_t(i) + prefetch_distance]);
      visit_particle(ps, loc[i], [&](auto& fp) { fp.copyFromForce(force_[i]); });
    });
  }

  // ---- read access (also the extension point for a local essential tree) --------
  const Octree<D>& octree() const { return tree_; }
  /// The imports' own tree (load_imports_apart; else empty or stale).
  const Octree<D>& import_tree() const { return itree_; }
  /// i-groups as ranges of sortedEPI(), in key order.
  const std::vector<IndexRange>& groups() const { return groups_; }
  std::span<const EPI> sortedEPI() const { return epi_; }
  /// Local particles [0, n_local) then imported ones, each in key order.
  std::span<const EPJ> sortedEPJ() const { return epj_; }
  /// Results of local particles in key order; sortedIndex(i) is the particle-system
  /// index of sorted particle i.
  std::span<const Force> sortedForce() const { return force_; }
  std::uint32_t sortedIndex(std::size_t i) const { return tree_.sorted(ItemKind::local)[i]; }
  std::size_t numberOfLocalParticles() const { return n_local_; }

 protected:
  Octree<D> tree_, itree_;
  std::vector<dvec> pos_, ipos_;
  std::vector<ItemKind> ikind_;
  std::vector<ItemKind> kind_;
  std::vector<IndexRange> groups_;
  std::vector<EPI> epi_;
  std::vector<EPJ> epj_;
  std::vector<Force> force_;
  std::vector<EPJ> imported_epj_;
  using spj_storage = std::conditional_t<std::is_void_v<SPJ>, char, SPJ>;
  std::vector<spj_storage> imported_spj_, spj_imported_sorted_;
  /// Bounding boxes of the cells the imported super-particles stand for (empty: points).
  std::vector<Box<double, D>> imported_spj_box_, spj_box_imported_sorted_;
  std::size_t n_local_ = 0;
};

}  // namespace pik::detail
