/// \file ShortRangeTree.hpp
/// \brief Neighbour search: short-range forces through a kernel, and neighbour lists.
///
/// Same octree and i-groups as the long-range tree. For each group the walk collects
/// the j-particles that can be a neighbour of some i in the group: j is kept when its
/// distance to the group's bounding box is below the search radius of the mode
/// (gather: the group's largest r_i; scatter: r_j; symmetric: the larger of the two).
/// The kernel gets these candidates and applies the exact cut itself, as in FDPS.
/// The tests are the same expressions in every mode, so when every particle has the
/// same radius the three modes hand the kernel identical lists (bitwise identical
/// results).
///
/// Periodic dimensions: the walk visits every periodic image of the tree that can
/// reach the group's search box, in a fixed order, and hands the kernel shifted
/// copies of the j-particles (setPos). Radii larger than the box simply visit more
/// images: a j-particle can then appear several times, once per image in range.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <type_traits>
#include <vector>

#include "pik/Boundary.hpp"
#include "pik/Box.hpp"
#include "pik/Error.hpp"
#include "pik/Profiler.hpp"
#include "pik/detail/Threads.hpp"
#include "pik/detail/TreeCore.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/particle/ParticleSystem.hpp"
#include "pik/tree/TreeParams.hpp"
#include "pik/walk/ListMode.hpp"
#include "pik/walk/SearchMode.hpp"

namespace pik {

template <class Force, class EPI, class EPJ, SearchMode Mode>
class ShortRangeTree : public detail::TreeCore<EPI, EPJ, Force, void, dim_of<EPJ>> {
  static_assert(HasPos<EPI>, "pik: the EPI type needs `getPos()` returning its position vector");
  static_assert(HasPos<EPJ>, "pik: the EPJ type needs `getPos()` returning its position vector");
  static_assert(Mode == SearchMode::scatter || HasRSearch<EPI>,
                "pik: gather and symmetric search need `getRSearch()` on the EPI type");
  static_assert(Mode == SearchMode::gather || HasRSearch<EPJ>,
                "pik: scatter and symmetric search need `getRSearch()` on the EPJ type");
  static_assert(ForceResult<Force>, "pik: the FORCE type needs `clear()` (kernels accumulate into it)");

 public:
  static constexpr int dim = dim_of<EPJ>;
  static constexpr SearchMode mode = Mode;
  using dvec = Vec<double, dim>;

  /// A neighbour found by a query: sorted EPJ index and the periodic image shift.
  struct Neighbour {
    std::uint32_t j;
    dvec shift;
  };

  explicit ShortRangeTree(TreeParams p = {}, Boundary<dim> b = Boundary<dim>::open())
      : params_(p), boundary_(b) {
    params_.check();
  }

  TreeParams& params() { return params_; }
  const Boundary<dim>& boundary() const { return boundary_; }
  void setBoundary(const Boundary<dim>& b) { boundary_ = b; }
  Profiler& profile() { return prof_; }

  /// Builds the tree over a particle system (for queries; the force calls do it too).
  template <class FP>
  void build(const ParticleSystem<FP>& ps) {
    this->load_and_build(ps, params_, prof_);
    check_inside_box(ps);
    compute_cells();
    lists_kept_ = false;
  }

  /// Keeps the tree of the last build and takes the particles' new contents (h and
  /// search radii; positions too, if they moved): every particle is copied again and
  /// the cells' boxes and largest radii are recomputed, the topology (Morton order,
  /// cells, groups) is kept. A walk on a refreshed tree hands kernels exactly the
  /// neighbours a rebuilt tree would (the tests use the recomputed tight boxes); only
  /// its cost grows as particles drift away from the order they were sorted in. For
  /// the passes of a smoothing-length iteration (positions fixed, h changing) and for
  /// several kernels at the same positions. Same particles in the same order as the
  /// build (else an error). Profiled as "tree refresh".
  template <class FP>
  void refresh(const ParticleSystem<FP>& ps) {
    if (cells_.empty() && ps.size() > 0) throw Error("refresh: the tree was never built");
    if (ps.size() != this->n_local_ || !this->imported_epj_.empty() || this->epj_.size() != this->n_local_)
      throw Error("refresh needs the particles of the last build (had " + std::to_string(this->n_local_) +
                  ", now " + std::to_string(ps.size()) + ") and no imported ones");
    reload_contents(ps);
  }

  /// Builds over `ps` with the topology of another short-range tree built over the same
  /// particles at the same positions (any force type and mode; e.g. a density tree
  /// lends its octree to the hydro-force tree of the same step): the Morton sort and
  /// the cell split are skipped, particles are copied and cell boxes and radii
  /// computed, so the result is that of build(ps). Profiled as "tree refresh".
  template <class Other, class FP>
  void buildLike(const Other& other, const ParticleSystem<FP>& ps) {
    if (other.numberOfLocalParticles() != ps.size() || other.sortedEPJ().size() != ps.size() ||
        !this->imported_epj_.empty())
      throw Error("buildLike: the other tree holds " + std::to_string(other.numberOfLocalParticles()) +
                  " particles (with imports: " + std::to_string(other.sortedEPJ().size()) + "), this system " +
                  std::to_string(ps.size()) + "; both need the same particles and no imports");
    {
      auto t = prof_.scope("tree refresh");
      this->tree_ = other.octree();
      this->groups_ = other.groups();
      this->n_local_ = ps.size();
      this->kind_.clear();
      this->epi_.resize(ps.size());
      this->epj_.resize(ps.size());
      this->force_.resize(ps.size());
      this->pos_.resize(ps.size());
      for (std::size_t i = 0; i < ps.size(); ++i) this->pos_[i] = detail::to_dvec<dim>(ps[i].getPos());
    }
    reload_contents(ps);
    check_inside_box(ps);
  }

  /// The walk on the tree as it is (after build(), refresh() or buildLike()), for the
  /// groups that hold at least one particle with active[i] != 0 (i: particle-system
  /// index; an empty span: every group); only those groups' particles get results
  /// written back, the others keep theirs. A smoothing-length pass uses it to
  /// recompute only the particles whose h changed (and their group mates, which get
  /// the values they had: same h, same neighbours).
  template <class FP, class K>
  void calcForceOnTreeAndWriteBack(K&& kernel, ParticleSystem<FP>& ps, std::span<const std::uint8_t> active = {}) {
    static_assert(PairKernel<std::remove_reference_t<K>, EPI, EPJ, Force>,
                  "pik: kernel must be callable as kernel(const EPI*, int, const EPJ*, int, FORCE*)");
    if (ps.size() != this->n_local_ || this->epi_.size() != ps.size())
      throw Error("calcForceOnTreeAndWriteBack: the tree holds " + std::to_string(this->n_local_) +
                  " particles, the system " + std::to_string(ps.size()) + " (build or refresh first)");
    if (!active.empty() && active.size() != ps.size())
      throw Error("calcForceOnTreeAndWriteBack: the active mask has " + std::to_string(active.size()) +
                  " entries for " + std::to_string(ps.size()) + " particles");
    const auto& groups = this->groups_;
    const auto& loc = this->tree_.sorted(ItemKind::local);
    group_on_.assign(groups.size(), 1);
    if (!active.empty())
      detail::parallel_for_static(std::ptrdiff_t(groups.size()), [&](std::ptrdiff_t g) {
        unsigned char on = 0;
        for (std::uint32_t i = groups[std::size_t(g)].begin; i < groups[std::size_t(g)].end && !on; ++i)
          on = active[loc[i]] != 0;
        group_on_[std::size_t(g)] = on;
      });
    walk(kernel, ListMode::rebuild, &group_on_);
    auto t = prof_.scope("write back");
    detail::parallel_for_static(std::ptrdiff_t(groups.size()), [&](std::ptrdiff_t g) {
      if (!group_on_[std::size_t(g)]) return;
      for (std::uint32_t i = groups[std::size_t(g)].begin; i < groups[std::size_t(g)].end; ++i)
        ps[loc[i]].copyFromForce(this->force_[i]);
    });
  }
  /// Groups walked by the last calcForceOnTreeAndWriteBack (all, for the other calls).
  std::size_t groupsWalked() const { return n_groups_walked_; }

  /// The one call: build, walk, kernel, write back.
  template <class FP, class K>
  void calcForceAllAndWriteBack(K&& kernel, ParticleSystem<FP>& ps, ListMode lm = ListMode::rebuild) {
    calcForceAll(kernel, ps, lm);
    this->write_back(ps, prof_);
  }

  template <class FP, class K>
  void calcForceAll(K&& kernel, const ParticleSystem<FP>& ps, ListMode lm = ListMode::rebuild) {
    static_assert(PairKernel<std::remove_reference_t<K>, EPI, EPJ, Force>,
                  "pik: kernel must be callable as kernel(const EPI*, int, const EPJ*, int, FORCE*)");
    if (lm == ListMode::reuse) {
      if (!lists_kept_) throw Error("ListMode::reuse needs a previous call with ListMode::make_for_reuse");
      this->reload(ps, prof_);
    } else {
      build(ps);
    }
    walk(kernel, lm);
    if (lm == ListMode::make_for_reuse) lists_kept_ = true;
  }

  /// Neighbours of one particle (exact: |x_i - (x_j + shift)| < r, r by the mode,
  /// distances in double), as shifted EPJ copies. Needs a built tree.
  void getNeighborList(const EPI& epi, std::vector<EPJ>& out) const {
    std::vector<Neighbour> nb;
    neighbours(epi, nb);
    out.clear();
    for (const Neighbour& n : nb) out.push_back(shifted(this->epj_[n.j], n.shift));
  }
  /// Neighbours of one particle as particle-system indices (imported particles:
  /// n_local + their position in setImportedParticles' vector); a particle appears
  /// once per periodic image in range.
  void neighbourIndices(const EPI& epi, std::vector<std::size_t>& out) const {
    std::vector<Neighbour> nb;
    neighbours(epi, nb);
    out.clear();
    const std::size_t nl = this->n_local_;
    const auto& imp = this->tree_.sorted(ItemKind::imported_particle);
    for (const Neighbour& n : nb)
      out.push_back(n.j < nl ? this->sortedIndex(n.j) : std::size_t(imp[n.j - nl]));
  }
  void neighbours(const EPI& epi, std::vector<Neighbour>& out) const {
    out.clear();
    if (cells_.empty()) return;
    const dvec xi = detail::to_dvec<dim>(epi.getPos());
    double ri = 0;
    if constexpr (Mode != SearchMode::scatter) ri = double(epi.getRSearch());
    Box<double, dim> g;
    g.extend(xi);
    std::vector<std::uint32_t> stack;
    std::vector<Candidate> cand;
    std::vector<dvec> shifts;
    collect(g, ri, stack, shifts, cand);
    for (const Candidate& c : cand) {
      const EPJ& pj = this->epj_[c.j];
      const dvec xj = detail::to_dvec<dim>(pj.getPos());
      double r = ri;
      if constexpr (Mode == SearchMode::scatter) r = double(pj.getRSearch());
      if constexpr (Mode == SearchMode::symmetric) r = std::max(ri, double(pj.getRSearch()));
      double d2 = 0;
      for (int d = 0; d < dim; ++d) {
        const double dx = xi[d] - (xj[d] + shifts[c.shift][d]);
        d2 += dx * dx;
      }
      if (d2 < r * r) out.push_back({c.j, shifts[c.shift]});
    }
  }

  /// j-particles from other ranks (with their search radii), added at the next build.
  void setImportedParticles(std::vector<EPJ> epj) { this->imported_epj_ = std::move(epj); }
  void clearImported() { this->imported_epj_.clear(); }
  /// Per-cell tight box of positions and largest j search radius (for deciding what
  /// to send to other ranks).
  std::span<const Box<double, dim>> cellBoxes() const { return boxes_; }
  std::span<const double> cellRSearch() const { return rmax_; }
  /// Candidates handed to kernels in the last walk, summed over i-particles.
  std::uint64_t interactions() const { return n_int_; }

 private:
  struct Candidate {
    std::uint32_t j;
    std::uint32_t shift;  ///< index into shifts_ of this walk
  };
  struct alignas(64) Scratch {
    std::vector<std::uint32_t> stack;
    std::vector<Candidate> cand;
    std::vector<dvec> shifts;
    std::vector<EPJ> epj;
    std::uint64_t n = 0;
  };

  /// Copies every particle again in the tree's order, recomputes the cell boxes and radii.
  template <class FP>
  void reload_contents(const ParticleSystem<FP>& ps) {
    {
      auto t = prof_.scope("tree refresh");
      ps.checkPositions();
      const auto& loc = this->tree_.sorted(ItemKind::local);
      detail::parallel_for_static(std::ptrdiff_t(this->n_local_), [&](std::ptrdiff_t i) {
        const FP& fp = ps[loc[std::size_t(i)]];
        this->epi_[std::size_t(i)].copyFromFP(fp);
        this->epj_[std::size_t(i)].copyFromFP(fp);
      });
    }
    compute_cells();
    lists_kept_ = false;
  }

  template <class FP>
  void check_inside_box(const ParticleSystem<FP>&) const {
    if (!boundary_.any_periodic()) return;
    if constexpr (!HasSetPos<EPJ>) {
      throw Error("periodic boundaries need `setPos(v)` on the EPJ type (kernels get shifted images)");
    }
    for (std::size_t i = 0; i < this->n_local_; ++i) {
      const dvec& x = this->pos_[i];  // item i is particle i of the particle system
      for (int d = 0; d < dim; ++d)
        if (boundary_.periodic[d] && !(x[d] >= boundary_.box.lo[d] && x[d] < boundary_.box.hi[d]))
          throw Error("particle " + std::to_string(i) +
                      " lies outside the periodic box in dimension " + std::to_string(d) +
                      " (coordinate " + std::to_string(x[d]) + "); call ParticleSystem::wrapPositions first");
    }
  }

  void compute_cells() {
    auto t = prof_.scope("moments");
    const auto& cells = this->tree_.cells();
    const std::size_t nc = cells.size(), nl = this->n_local_;
    boxes_.assign(nc, Box<double, dim>{});
    rmax_.assign(nc, 0.0);
    cells_ = cells;
    for (std::size_t c = nc; c-- > 0;) {
      const auto& cell = cells[c];
      Box<double, dim> box;
      double r = 0;
      if (cell.leaf()) {
        auto add = [&](const EPJ& p) {
          box.extend(detail::to_dvec<dim>(p.getPos()));
          if constexpr (Mode != SearchMode::gather) r = std::max(r, double(p.getRSearch()));
        };
        for (std::uint32_t j = cell.kind_begin[0]; j < cell.kind_end[0]; ++j) add(this->epj_[j]);
        for (std::uint32_t j = cell.kind_begin[1]; j < cell.kind_end[1]; ++j) add(this->epj_[nl + j]);
      } else {
        for (std::uint32_t k = cell.child; k < cell.child + cell.n_child; ++k)
          box.extend(boxes_[k]), r = std::max(r, rmax_[k]);
      }
      boxes_[c] = box;
      rmax_[c] = r;
    }
  }

  /// Fills shifts_ for a search box: every periodic image of the tree's box that can
  /// reach it, in a fixed order (first dimension slowest, shifts ascending).
  void image_shifts(const Box<double, dim>& search, std::vector<dvec>& shifts) const {
    shifts.assign(1, dvec{});
    for (int d = 0; d < dim; ++d) {
      if (!boundary_.periodic[d]) continue;
      const double L = boundary_.period(d);
      const long kmin = long(std::floor((search.lo[d] - boxes_[0].hi[d]) / L));
      const long kmax = long(std::ceil((search.hi[d] - boxes_[0].lo[d]) / L));
      std::vector<dvec> next;
      for (const dvec& s : shifts)
        for (long k = kmin; k <= kmax; ++k) {
          dvec t = s;
          t[d] = double(k) * L;
          next.push_back(t);
        }
      shifts.swap(next);
    }
  }

  /// Candidates for a group box g with largest i radius ri: j kept when
  /// dist(g, x_j + shift) <= r (r by the mode), cells pruned when farther.
  void collect(const Box<double, dim>& g, double ri, std::vector<std::uint32_t>& stack,
               std::vector<dvec>& shifts, std::vector<Candidate>& cand) const {
    // Slack for rounding in box distances; the exact cut is applied by the caller.
    constexpr double slack = 1 + 1e-12;
    const std::size_t nl = this->n_local_;
    double reach = ri;
    if constexpr (Mode != SearchMode::gather) reach = std::max(ri, rmax_[0]);
    cand.clear();
    image_shifts(g.grown(reach * slack), shifts);
    for (std::uint32_t s = 0; s < shifts.size(); ++s) {
      const dvec& sh = shifts[s];
      stack.clear();
      stack.push_back(0);
      while (!stack.empty()) {
        const std::uint32_t c = stack.back();
        stack.pop_back();
        Box<double, dim> b = boxes_[c];
        b.lo += sh, b.hi += sh;
        double r = ri;
        if constexpr (Mode == SearchMode::scatter) r = rmax_[c];
        if constexpr (Mode == SearchMode::symmetric) r = std::max(ri, rmax_[c]);
        if (g.distance2(b) > r * r * slack) continue;
        const auto& cell = cells_[c];
        if (cell.leaf()) {
          auto test = [&](std::uint32_t j) {
            const EPJ& p = this->epj_[j];
            double rj = ri;
            if constexpr (Mode == SearchMode::scatter) rj = double(p.getRSearch());
            if constexpr (Mode == SearchMode::symmetric) rj = std::max(ri, double(p.getRSearch()));
            if (g.distance2(detail::to_dvec<dim>(p.getPos()) + sh) <= rj * rj * slack) cand.push_back({j, s});
          };
          for (std::uint32_t j = cell.kind_begin[0]; j < cell.kind_end[0]; ++j) test(j);
          for (std::uint32_t j = cell.kind_begin[1]; j < cell.kind_end[1]; ++j) test(std::uint32_t(nl + j));
        } else {
          for (std::uint32_t k = cell.n_child; k-- > 0;) stack.push_back(cell.child + k);
        }
      }
    }
  }

  EPJ shifted(const EPJ& p, const dvec& sh) const {
    if constexpr (HasSetPos<EPJ>) {
      bool zero = true;
      for (int d = 0; d < dim; ++d) zero = zero && sh[d] == 0;
      if (zero) return p;
      EPJ q = p;
      auto x = q.getPos();
      using T = std::remove_cvref_t<decltype(x.x)>;
      x.x = T(double(x.x) + sh[0]);
      x.y = T(double(x.y) + sh[1]);
      if constexpr (dim == 3) x.z = T(double(x.z) + sh[2]);
      q.setPos(x);
      return q;
    } else {
      return p;
    }
  }

  template <class K>
  void walk(K& kernel, ListMode lm, const std::vector<unsigned char>* group_on = nullptr) {
    auto t = prof_.scope("walk+kernel");
    const auto& groups = this->groups_;
    scratch_.resize(std::size_t(detail::max_threads()));
    for (Scratch& s : scratch_) s.n = 0;
    n_groups_walked_ = groups.size();
    if (group_on) n_groups_walked_ = std::size_t(std::count(group_on->begin(), group_on->end(), 1));
    if (lm == ListMode::make_for_reuse) kept_.assign(groups.size(), Kept{});
    if (lm == ListMode::reuse && kept_.size() != groups.size())
      throw Error("kept neighbour lists do not match the tree");
    detail::parallel_for(std::ptrdiff_t(groups.size()), [&](std::ptrdiff_t g, int thread) {
      if (group_on && !(*group_on)[std::size_t(g)]) return;
      Scratch& s = scratch_[std::size_t(thread)];
      const std::uint32_t ib = groups[std::size_t(g)].begin, ie = groups[std::size_t(g)].end;
      std::vector<Candidate>* cand = &s.cand;
      std::vector<dvec>* shifts = &s.shifts;
      if (lm == ListMode::reuse) {
        cand = &kept_[std::size_t(g)].cand;
        shifts = &kept_[std::size_t(g)].shifts;
      } else {
        Box<double, dim> gbox;
        double ri = 0;
        for (std::uint32_t i = ib; i < ie; ++i) {
          gbox.extend(detail::to_dvec<dim>(this->epi_[i].getPos()));
          if constexpr (Mode != SearchMode::scatter) ri = std::max(ri, double(this->epi_[i].getRSearch()));
        }
        if (lm == ListMode::make_for_reuse) {
          cand = &kept_[std::size_t(g)].cand;
          shifts = &kept_[std::size_t(g)].shifts;
        }
        collect(gbox, ri, s.stack, *shifts, *cand);
      }
      s.epj.clear();
      for (const Candidate& c : *cand) s.epj.push_back(shifted(this->epj_[c.j], (*shifts)[c.shift]));
      Force* f = this->force_.data() + ib;
      const int ni = int(ie - ib);
      for (int i = 0; i < ni; ++i) f[i].clear();
      if (!s.epj.empty()) kernel(this->epi_.data() + ib, ni, s.epj.data(), int(s.epj.size()), f);
      s.n += std::uint64_t(ni) * s.epj.size();
    });
    n_int_ = 0;
    for (const Scratch& s : scratch_) n_int_ += s.n;
  }

  struct Kept {
    std::vector<Candidate> cand;
    std::vector<dvec> shifts;
  };

  TreeParams params_;
  Boundary<dim> boundary_;
  Profiler prof_;
  std::vector<typename Octree<dim>::Cell> cells_;
  std::vector<Box<double, dim>> boxes_;
  std::vector<double> rmax_;
  std::vector<Scratch> scratch_;
  std::vector<Kept> kept_;
  bool lists_kept_ = false;
  std::uint64_t n_int_ = 0;
  std::vector<unsigned char> group_on_;
  std::size_t n_groups_walked_ = 0;
};

}  // namespace pik
