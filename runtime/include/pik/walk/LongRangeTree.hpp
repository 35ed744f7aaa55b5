/// \file LongRangeTree.hpp
/// \brief Barnes–Hut force with group walks: gravity-like forces through a kernel.
///
/// The modified tree algorithm (Barnes 1990, J. Comput. Phys. 87, 161): the i-particles
/// of a small cell (an i-group, at most n_group_limit particles) share one interaction
/// list, built once for the group's bounding box, of j-particles (EPJ, from opened
/// leaves) and super-particles (SPJ, cells far enough away to be used whole). The
/// kernels are then called once per group,
///
///     kernel   (epi, ni, epj, nj,  force)
///     kernel_sp(epi, ni, spj, nsp, force)
///
/// with force cleared first (kernels accumulate). Groups run in parallel; each group's
/// list and the order of its sums do not depend on the thread count, so results are
/// bitwise identical for any number of threads.
///
/// A cell is used whole when its bounding box does not overlap the group's box and
/// s < theta * d, s the largest side of the cell's tight bounding box and d the
/// distance from the group's box to the cell's box (Opening::box, the default, as
/// in FDPS) or to the cell's centre of mass (Opening::centre_of_mass: fewer
/// interactions and larger errors at the same theta), or d > s / theta + delta with
/// delta the offset of the centre of mass from the box centre
/// (Opening::centre_of_mass_offset; see TreeParams.hpp).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <type_traits>
#include <utility>
#include <vector>

#include "pik/Box.hpp"
#include "pik/Error.hpp"
#include "pik/Profiler.hpp"
#include "pik/detail/Threads.hpp"
#include "pik/detail/TreeCore.hpp"
#include "pik/detail/WalkCells.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/particle/ParticleSystem.hpp"
#include "pik/particle/Species.hpp"
#include "pik/tree/Multipole.hpp"
#include "pik/tree/SuperParticle.hpp"
#include "pik/tree/TreeParams.hpp"
#include "pik/walk/InteractionList.hpp"
#include "pik/walk/ListMode.hpp"

#if defined(__AVX512F__)
#include <immintrin.h>
#endif

namespace pik {

namespace detail {
template <class EPJ>
using default_spj = SPJMonopole<typename pos_type_of<EPJ>::value_type, dim_of<EPJ>>;
}  // namespace detail

/// Long-range (gravity-like) tree. FORCE, EPI, EPJ are the user's types; SPJ is
/// SPJMonopole (default), SPJQuadrupole or a user type satisfying SuperParticle.
template <class Force, class EPI, class EPJ, class SPJ = detail::default_spj<EPJ>>
class LongRangeTree : public detail::TreeCore<EPI, EPJ, Force, SPJ, dim_of<EPJ>> {
  static_assert(HasPos<EPI>, "pik: the EPI type needs `getPos()` returning its position vector");
  static_assert(HasPos<EPJ>, "pik: the EPJ type needs `getPos()` returning its position vector");
  static_assert(HasCharge<EPJ>,
                "pik: the EPJ type needs `getCharge()` (the mass of a j-particle) for a long-range tree");
  static_assert(ForceResult<Force>, "pik: the FORCE type needs `clear()` (kernels accumulate into it)");
  static_assert(SuperParticle<SPJ>,
                "pik: the SPJ type needs order, dim, setMoments(Multipole) and getMoments()");

 public:
  static constexpr int dim = dim_of<EPJ>;
  static_assert(SPJ::dim == dim, "pik: SPJ and EPJ dimensions differ");
  using Base = detail::TreeCore<EPI, EPJ, Force, SPJ, dim>;
  using dvec = Vec<double, dim>;

  explicit LongRangeTree(TreeParams p = {}) : params_(p) { params_.check(); }

  TreeParams& params() { return params_; }
  const TreeParams& params() const { return params_; }
  Profiler& profile() { return prof_; }

  /// The one call: build the tree, walk, call the kernels, write results back into
  /// the particle system with copyFromForce. `ps` is a pik::ParticleSystem or a
  /// pik::Species bundle of several (one tree over all; each result goes back to
  /// the particle of its own species).
  template <class PS, class K, class KS>
    requires ParticleSource<PS>
  void calcForceAllAndWriteBack(K&& kernel, KS&& kernel_sp, PS&& ps,
                                ListMode mode = ListMode::rebuild) {
    calcForceAll(kernel, kernel_sp, ps, mode);
    this->write_back(ps, prof_);
  }

  /// Everything but the write-back: results stay in sortedForce().
  template <ParticleSource PS, class K, class KS>
  void calcForceAll(K&& kernel, KS&& kernel_sp, const PS& ps,
                    ListMode mode = ListMode::rebuild) {
    static_assert(PairKernel<std::remove_reference_t<K>, EPI, EPJ, Force>,
                  "pik: kernel must be callable as kernel(const EPI*, int, const EPJ*, int, FORCE*)");
    static_assert(PairKernel<std::remove_reference_t<KS>, EPI, SPJ, Force>,
                  "pik: kernel_sp must be callable as kernel_sp(const EPI*, int, const SPJ*, int, FORCE*)");
    if (mode == ListMode::reuse) {
      if (!lists_kept_)
        throw Error("ListMode::reuse needs a previous call with ListMode::make_for_reuse");
      this->reload(ps, prof_);
    } else {
      this->load_and_build(ps, params_, prof_);
      lists_kept_ = false;
    }
    compute_moments();
    local_only_ = false;
    walk(kernel, kernel_sp, mode);
    if (mode == ListMode::make_for_reuse) lists_kept_ = true;
  }

  // ---- extension point for distributed runs (local essential tree) ---------------
  /// j-particles from other ranks, added to the next tree build as j-only items.
  void setImportedParticles(std::vector<EPJ> epj) { this->imported_epj_ = std::move(epj); }
  /// Super-particles from other ranks (cells the sender found far enough from this
  /// rank's whole domain); they join the tree as point multipoles.
  void setImportedSuperParticles(std::vector<SPJ> spj) {
    this->imported_spj_ = std::move(spj);
    this->imported_spj_box_.clear();
  }
  /// The same with the bounding box of the cell each super-particle stands for: the
  /// receiving cells' boxes then cover that extent, so the opening criterion sees
  /// their true size (as points they would look too small and open too late).
  void setImportedSuperParticles(std::vector<SPJ> spj, std::vector<Box<double, dim>> extents) {
    if (extents.size() != spj.size())
      throw Error("setImportedSuperParticles: " + std::to_string(extents.size()) + " extents for " +
                  std::to_string(spj.size()) + " super-particles");
    this->imported_spj_ = std::move(spj);
    this->imported_spj_box_ = std::move(extents);
  }
  void clearImported() {
    this->imported_epj_.clear();
    this->imported_spj_.clear();
    this->imported_spj_box_.clear();
  }
  /// Builds the tree and its moments without walking (for cellMoments(),
  /// cellBoxes(), octree(), sortedEPJ(): e.g. to choose what to send other ranks).
  template <ParticleSource PS>
  void buildTreeAndMoments(const PS& ps) {
    this->load_and_build(ps, params_, prof_);
    lists_kept_ = false;
    compute_moments();
    local_only_ = this->imported_epj_.empty() && this->imported_spj_.empty();
  }
  /// The distributed step without a second build of the local tree: after
  /// buildTreeAndMoments(ps) (no imports) and setImported*, the imports get a small
  /// tree of their own, and every i-group's walk visits the local tree and then the
  /// imports' tree (each cell judged by the same opening criterion); then the kernels
  /// and the write-back. The local tree's cells, moments and groups are kept.
  template <class PS, class K, class KS>
    requires ParticleSource<PS>
  void calcForceWithImportsAndWriteBack(K&& kernel, KS&& kernel_sp, PS&& ps) {
    static_assert(PairKernel<std::remove_reference_t<K>, EPI, EPJ, Force>,
                  "pik: kernel must be callable as kernel(const EPI*, int, const EPJ*, int, FORCE*)");
    static_assert(PairKernel<std::remove_reference_t<KS>, EPI, SPJ, Force>,
                  "pik: kernel_sp must be callable as kernel_sp(const EPI*, int, const SPJ*, int, FORCE*)");
    if (!local_only_ || ps.size() != this->n_local_)
      throw Error("calcForceWithImportsAndWriteBack needs buildTreeAndMoments over the same particles first");
    this->load_imports_apart(params_, prof_);
    local_only_ = false;
    with_imports_ = this->imported_epj_.size() + this->imported_spj_.size() > 0;
    {
      auto t = prof_.scope("moments");
      const std::size_t nc = this->tree_.cells().size(), ns = this->spj_imported_sorted_.size();
      const auto& icells = this->import_tree().cells();
      spj_.resize(nc + ns + (with_imports_ ? icells.size() : 0));
      for (std::size_t i = 0; i < ns; ++i) spj_[nc + i] = this->spj_imported_sorted_[i];
      if (with_imports_) {
        imoments_.resize(icells.size());  // every cell is written by moments_of
        iboxes_.resize(icells.size());
        iwalk_cells_.layout(icells);
        moments_of(icells, imoments_, iboxes_, iwalk_cells_, this->n_local_, nc + ns);
      }
    }
    walk(kernel, kernel_sp, ListMode::rebuild);
    this->write_back(ps, prof_);
  }

  /// Moments of every cell (index like octree().cells()), for building what to send.
  std::span<const Multipole<dim>> cellMoments() const { return moments_; }
  /// Tight bounding box of every cell's items.
  std::span<const Box<double, dim>> cellBoxes() const { return boxes_; }

  /// Interactions of the last walk: j-particles and super-particles, summed over
  /// i-particles.
  std::uint64_t interactionsEP() const { return n_ep_; }
  std::uint64_t interactionsSP() const { return n_sp_; }
  /// Blocks of sibling cells the last walk judged, summed over i-groups: the work of
  /// list making (deterministic, unlike its time).
  std::uint64_t blocksVisited() const { return n_visit_; }
  /// The kept list of i-group g (after ListMode::make_for_reuse).
  const InteractionList& interactionList(std::size_t g) const { return lists_.at(g); }

 private:

  struct alignas(64) Scratch {
    std::vector<std::uint32_t> level, next;  ///< blocks to visit at this depth and the next
    InteractionList list;
    std::vector<EPJ> epj;
    std::vector<SPJ> spj;
    double t_walk = 0, t_kernel = 0;
    std::uint64_t n_ep = 0, n_sp = 0, n_visit = 0;
  };

  void compute_moments() {
    auto t = prof_.scope("moments");
    const auto& cells = this->tree_.cells();
    const std::size_t nc = cells.size();
    with_imports_ = false;
    // Not cleared: moments_of writes every cell (clearing them would be two serial
    // passes over tens of megabytes per step).
    moments_.resize(nc);
    boxes_.resize(nc);
    walk_cells_.layout(cells);
    spj_.resize(nc + this->spj_imported_sorted_.size());
    moments_of(cells, moments_, boxes_, walk_cells_, 0, 0);
    for (std::size_t i = 0; i < this->spj_imported_sorted_.size(); ++i)
      spj_[nc + i] = this->spj_imported_sorted_[i];
  }

  /// Moments, boxes and walk blocks of a tree's cells: its item kind 0 are
  /// sortedEPJ()[epj0 + j], kind 1 [n_local + j], kind 2 the imported
  /// super-particles; cell c's super-particle goes to spj_[spj0 + c].
  template <class Cells>
  void moments_of(const Cells& cells, std::vector<Multipole<dim>>& moments, std::vector<Box<double, dim>>& boxes,
                  detail::WalkCells<dim>& wc, std::size_t epj0, std::size_t spj0) {
    const std::size_t nc = cells.size();
    if (nc == 0) return;
    // One bottom-up pass. Breadth-first cells have non-decreasing depth, so the
    // cells of depth `top` are a contiguous range, and their subtrees are disjoint:
    // each subtree is done on one thread in post order (children before parents),
    // with no barrier between levels; then the few cells above, in reverse order.
    constexpr std::uint16_t top = 3;
    std::size_t rb = 0;
    while (rb < nc && cells[rb].depth < top) ++rb;
    std::size_t re = rb;
    while (re < nc && cells[re].depth == top) ++re;
    if (re > rb) {
      detail::parallel_for(std::ptrdiff_t(re - rb), [&](std::ptrdiff_t k, int) {
        subtree_moments(cells, moments, boxes, wc, epj0, spj0, rb + std::size_t(k));
      });
    }
    for (std::size_t c = rb; c-- > 0;) cell_moments(cells, moments, boxes, wc, epj0, spj0, c);
  }

  /// Moments of cell c's subtree, children first (recursion depth <= tree depth).
  template <class Cells>
  void subtree_moments(const Cells& cells, std::vector<Multipole<dim>>& moments, std::vector<Box<double, dim>>& boxes,
                       detail::WalkCells<dim>& wc, std::size_t epj0, std::size_t spj0, std::size_t c) {
    const auto& cell = cells[c];
    for (std::uint32_t k = cell.child; k < cell.child + cell.n_child; ++k)
      subtree_moments(cells, moments, boxes, wc, epj0, spj0, k);
    cell_moments(cells, moments, boxes, wc, epj0, spj0, c);
  }

  template <class Cells>
  void cell_moments(const Cells& cells, std::vector<Multipole<dim>>& moments, std::vector<Box<double, dim>>& boxes,
                    detail::WalkCells<dim>& wc, std::size_t epj0, std::size_t spj0, std::size_t c) {
    const auto& cell = cells[c];
    Multipole<dim> m;
    Box<double, dim> box;
    dvec sum{};
    const std::size_t nl = this->n_local_;
    auto for_particles = [&](auto&& f) {
      for (std::uint32_t j = cell.kind_begin[0]; j < cell.kind_end[0]; ++j) f(this->epj_[epj0 + j]);
      for (std::uint32_t j = cell.kind_begin[1]; j < cell.kind_end[1]; ++j) f(this->epj_[nl + j]);
    };
    auto for_supers = [&](auto&& f) {
      for (std::uint32_t j = cell.kind_begin[2]; j < cell.kind_end[2]; ++j)
        f(this->spj_imported_sorted_[j].getMoments());
    };
    if (cell.leaf()) {
      for_particles([&](const EPJ& p) {
        dvec x = detail::to_dvec<dim>(p.getPos());
        double mj = double(p.getCharge());
        m.mass += mj;
        sum += x * mj;
        box.extend(x);
      });
      for_supers([&](const Multipole<dim>& s) {
        m.mass += s.mass;
        sum += s.pos * s.mass;
        box.extend(s.pos);
      });
      for (std::uint32_t j = cell.kind_begin[2]; j < cell.kind_end[2]; ++j)
        if (j < this->spj_box_imported_sorted_.size()) box.extend(this->spj_box_imported_sorted_[j]);
      m.pos = m.mass > 0 ? sum / m.mass : box.center();
      if constexpr (SPJ::order >= 2) {
        for_particles([&](const EPJ& p) {
          m.add_quadrupole_of_point(double(p.getCharge()), detail::to_dvec<dim>(p.getPos()));
        });
        for_supers([&](const Multipole<dim>& s) { m.add_quadrupole_of(s); });
      }
    } else {
      for (std::uint32_t k = cell.child; k < cell.child + cell.n_child; ++k) {
        m.mass += moments[k].mass;
        sum += moments[k].pos * moments[k].mass;
        box.extend(boxes[k]);
      }
      m.pos = m.mass > 0 ? sum / m.mass : box.center();
      if constexpr (SPJ::order >= 2) {
        for (std::uint32_t k = cell.child; k < cell.child + cell.n_child; ++k)
          m.add_quadrupole_of(moments[k]);
      }
    }
    moments[c] = m;
    boxes[c] = box;
    spj_[spj0 + c].setMoments(m);
    const double open2 = params_.opening_radius2(box, m.pos);
    wc.set(c, box, m.pos, open2, params_.distance_to_box());
  }

  /// Builds group g's list into `list` (tree order: depth by depth, key order within one).
  void make_list(const Box<double, dim>& gbox, Scratch& s, InteractionList& list) const {
    if (params_.distance_to_box()) {
      make_list_with<true>(gbox, s, list);
    } else {
      make_list_with<false>(gbox, s, list);
    }
  }

  template <bool to_box>
  void make_list_with(const Box<double, dim>& gbox, Scratch& s, InteractionList& list) const {
    list.clear();
    const std::uint32_t nl = std::uint32_t(this->n_local_), nc = std::uint32_t(this->tree_.cells().size());
    append_list<to_box>(gbox, s, list, walk_cells_, this->tree_.cells(), boxes_, 0, 0);
    if (with_imports_)
      append_list<to_box>(gbox, s, list, iwalk_cells_, this->import_tree().cells(), iboxes_, nl,
                          nc + std::uint32_t(this->spj_imported_sorted_.size()));
  }

  /// Appends what one tree gives an i-group: its item kind 0 are sortedEPJ()[epj0 +
  /// j], its cell c is spj_[spj0 + c] (see moments_of).
  template <bool to_box, class Cells>
  void append_list(const Box<double, dim>& gbox, Scratch& s, InteractionList& list,
                   const detail::WalkCells<dim>& wc, const Cells& cells,
                   const std::vector<Box<double, dim>>& boxes, std::uint32_t epj0,
                   std::uint32_t spj0) const {
    if (wc.blocks() == 0) return;
    const bool cut = std::isfinite(params_.r_cut);
    const double rcut2 = params_.r_cut * params_.r_cut;
    const std::uint32_t nl = std::uint32_t(this->n_local_), nc = std::uint32_t(this->tree_.cells().size());
    auto& level = s.level;
    auto& next = s.next;
    next.clear();
    // An opened cell's children are judged all at once (one block); far ones join
    // the list as super-particles, leaves give their particles, and the cells to open
    // are visited a depth at a time (breadth first, in key order within a depth):
    // their blocks are asked for (prefetched) a whole depth ahead, so that the
    // memory latency of one block overlaps with the judging of the others, where a
    // depth-first walk waits for nearly every block it visits.
    auto visit = [&](std::uint32_t bi) {
      ++s.n_visit;
      const auto& b = wc.block(bi);
      auto v = detail::WalkCells<dim>::template judge<to_box>(b, gbox);
      if (cut) {
        // Cells at least r_cut from the group's box give nothing: skipped. A far
        // cell that straddles the cut-off is opened instead of used whole, so the
        // kernel's cut applies to its particles one by one, not to its centre of mass.
        unsigned beyond = 0, straddle = 0;
        for (unsigned l = 0; l < b.n; ++l) {
          const auto& cb = boxes[b.first_cell + l];
          if (box_distance2(gbox, cb) >= rcut2) beyond |= 1u << l;
          else if ((v.far >> l & 1u) && box_reach2(gbox, cb) >= rcut2) straddle |= 1u << l;
        }
        v.leaf |= straddle & b.leaf;
        v.open |= straddle & ~unsigned(b.leaf);
        v.far &= ~(beyond | straddle), v.leaf &= ~beyond, v.open &= ~beyond;
      }
#if defined(__AVX512F__) && defined(__AVX512VL__)
      if constexpr (detail::WalkCells<dim>::lanes == 8) {
        // The far lanes' cell ids packed by one compress, in lane order as below (a
        // loop over the mask costs a mispredicted exit per block; at 2^20 ~6 of a
        // block's lanes are far on average). Compressed in a register and stored whole:
        // the lanes past the count are scratch that the next append overwrites.
        if (v.far) {
          const __m256i id = _mm256_add_epi32(_mm256_set1_epi32(int(spj0 + b.first_cell)),
                                              _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
          _mm256_storeu_si256(reinterpret_cast<__m256i*>(list.spj.room(8)),
                              _mm256_maskz_compress_epi32(__mmask8(v.far), id));
          list.spj.append(unsigned(std::popcount(v.far)));
        }
      } else
#endif
      {
        for (unsigned m = v.far; m; m &= m - 1)
          list.spj.push_back(spj0 + b.first_cell + unsigned(std::countr_zero(m)));
      }
      for (unsigned m = v.leaf; m; m &= m - 1) {
        const int l = std::countr_zero(m);
        add_range(list, epj0 + b.next[l], epj0 + b.leaf_end[l]);
        if (b.mixed & (1u << l)) {
          const auto& cell = cells[b.first_cell + unsigned(l)];
          list.add_epj(nl + cell.kind_begin[1], nl + cell.kind_end[1]);
          for (std::uint32_t j = cell.kind_begin[2]; j < cell.kind_end[2]; ++j) list.spj.push_back(nc + j);
        }
      }
      for (unsigned m = v.open; m; m &= m - 1) {
        const std::uint32_t nb = b.next[std::countr_zero(m)];
        wc.prefetch(nb, to_box);
        next.push_back(nb);
      }
    };
    visit(0);
    while (!next.empty()) {
      std::swap(level, next);
      next.clear();
      for (const std::uint32_t bi : level) visit(bi);
    }
  }

  /// InteractionList::add_epj, kept inline in the walk's loop.
  [[gnu::always_inline]] static inline void add_range(InteractionList& list, std::uint32_t b, std::uint32_t e) {
    if (b == e) return;
    if (!list.epj.empty() && list.epj.back().end == b) {
      list.epj.back().end = e;
    } else {
      list.epj.push_back({b, e});
    }
  }

  static double box_distance2(const Box<double, dim>& a, const Box<double, dim>& b) {
    double d2 = 0;
    for (int d = 0; d < dim; ++d) {
      const double e = std::max(std::max(a.lo[d] - b.hi[d], b.lo[d] - a.hi[d]), 0.0);
      d2 += e * e;
    }
    return d2;
  }

  /// Squared largest distance between a point of box a and a point of box b.
  static double box_reach2(const Box<double, dim>& a, const Box<double, dim>& b) {
    double d2 = 0;
    for (int d = 0; d < dim; ++d) {
      const double e = std::max(a.hi[d] - b.lo[d], b.hi[d] - a.lo[d]);
      d2 += e * e;
    }
    return d2;
  }

  template <class K, class KS>
  void walk(K& kernel, KS& kernel_sp, ListMode mode) {
    const double t0 = wall_time();
    const auto& groups = this->groups_;
    const int nt = detail::max_threads();
    scratch_.resize(std::size_t(nt));
    for (Scratch& s : scratch_) s.t_walk = s.t_kernel = 0, s.n_ep = s.n_sp = s.n_visit = 0;
    if (mode == ListMode::make_for_reuse) lists_.assign(groups.size(), InteractionList{});
    if (mode == ListMode::reuse && lists_.size() != groups.size())
      throw Error("kept interaction lists do not match the tree");
    detail::parallel_for(std::ptrdiff_t(groups.size()), [&](std::ptrdiff_t g, int thread) {
      Scratch& s = scratch_[std::size_t(thread)];
      const double ta = wall_time();
      const std::uint32_t ib = groups[std::size_t(g)].begin, ie = groups[std::size_t(g)].end;
      InteractionList* list = &s.list;
      if (mode == ListMode::reuse) {
        list = &lists_[std::size_t(g)];
      } else {
        Box<double, dim> gbox;
        for (std::uint32_t i = ib; i < ie; ++i) gbox.extend(detail::to_dvec<dim>(this->epi_[i].getPos()));
        if (mode == ListMode::make_for_reuse) list = &lists_[std::size_t(g)];
        make_list(gbox, s, *list);
      }
      // Gathered into arrays that only grow (their sizes are capacities).
      const std::size_t nj = list->epj_count(), ns = list->spj.size();
      if (s.epj.size() < nj) s.epj.resize(std::max(nj, 2 * s.epj.size()));
      if (s.spj.size() < ns) s.spj.resize(std::max(ns, 2 * s.spj.size()));
      EPJ* out = s.epj.data();
      for (const IndexRange& r : list->epj) out = std::copy(this->epj_.data() + r.begin, this->epj_.data() + r.end, out);
      const std::uint32_t* id = list->spj.data();
      for (std::size_t k = 0; k < ns; ++k) s.spj[k] = spj_[id[k]];
      const double tb = wall_time();
      Force* f = this->force_.data() + ib;
      const int ni = int(ie - ib);
      for (int i = 0; i < ni; ++i) f[i].clear();
      const EPI* epi = this->epi_.data() + ib;
      if (nj > 0) kernel(epi, ni, s.epj.data(), int(nj), f);
      if (ns > 0) kernel_sp(epi, ni, s.spj.data(), int(ns), f);
      const double tc = wall_time();
      s.t_walk += tb - ta;
      s.t_kernel += tc - tb;
      s.n_ep += std::uint64_t(ni) * nj;
      s.n_sp += std::uint64_t(ni) * ns;
    });
    // Split the wall time of the parallel loop between list making and kernels in
    // proportion to the threads' summed times.
    double tw = 0, tk = 0;
    n_ep_ = n_sp_ = n_visit_ = 0;
    for (const Scratch& s : scratch_)
      tw += s.t_walk, tk += s.t_kernel, n_ep_ += s.n_ep, n_sp_ += s.n_sp, n_visit_ += s.n_visit;
    const double wall = wall_time() - t0, frac = tw + tk > 0 ? tw / (tw + tk) : 0;
    prof_.add("walk", wall * frac);
    prof_.add("kernel", wall * (1 - frac));
  }

  TreeParams params_;
  Profiler prof_;
  std::vector<Multipole<dim>> moments_;
  std::vector<Box<double, dim>> boxes_;
  detail::WalkCells<dim> walk_cells_;
  /// The imports' own tree (calcForceWithImportsAndWriteBack): moments, boxes, blocks.
  std::vector<Multipole<dim>> imoments_;
  std::vector<Box<double, dim>> iboxes_;
  detail::WalkCells<dim> iwalk_cells_;
  bool local_only_ = false, with_imports_ = false;
  /// Cells [0, n_cells), then imported super-particles, then the imports' tree's cells.
  std::vector<SPJ> spj_;
  std::vector<Scratch> scratch_;
  std::vector<InteractionList> lists_;
  bool lists_kept_ = false;
  std::uint64_t n_ep_ = 0, n_sp_ = 0, n_visit_ = 0;
};

}  // namespace pik
