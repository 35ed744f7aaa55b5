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
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <memory>
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

namespace detail {
/// A candidate of a short-range walk: sorted EPJ index and periodic image index.
struct SrCandidate {
  std::uint32_t j;
  std::uint32_t shift;  ///< index into the walk's shifts
};
/// A cell as the candidate walk reads it, in one place: tight box, largest r_j (0 in
/// gather mode), children, local and imported particle ranges.
template <int dim>
struct SrNode {
  Box<double, dim> box;
  double rmax;
  std::uint32_t child, n_child;
  std::uint32_t lb, le, ib, ie;
};
/// A j-particle's position and search radius (0 in gather mode) in double.
template <int dim>
struct SrJRec {
  Vec<double, dim> x;
  double r;
};
/// Candidate lists kept across walks at the same positions and shared by the trees of
/// one step (ShortRangeTree::keepCandidates): each i-group's symmetric candidates for
/// the radii `reach` (every particle's search radius at collection times 1 + margin),
/// filled lazily, group by group, by whichever walk needs a list first.
template <int dim>
struct SharedCandidates {
  double margin = 0;
  std::vector<SrJRec<dim>> jrec;  ///< position and reach per sorted EPJ
  std::vector<SrNode<dim>> nodes;  ///< the tree's cells with rmax from the reaches
  std::vector<Box<double, dim>> gbox;  ///< the i-groups' boxes
  /// Each group's candidates: sorted EPJ indices, and their image-shift indices into
  /// `shifts` (empty where the group has one shift: open space needs 4 bytes a candidate).
  std::vector<std::vector<std::uint32_t>> cj, cs;
  std::vector<std::vector<Vec<double, dim>>> shifts;
  std::vector<std::uint8_t> have;
  std::uint64_t collected = 0;  ///< groups collected so far (statistics)
  std::vector<std::uint32_t> levels;  ///< first node of each depth, then the end (levels_up)
};

/// First cell of each depth level of a breadth-first cell array (depth never decreases
/// along it), then its end; found by bisection.
template <class Cells>
void level_starts(const Cells& cells, std::vector<std::uint32_t>& out) {
  out.clear();
  for (std::size_t b = 0; b < cells.size();) {
    out.push_back(std::uint32_t(b));
    const auto d = cells[b].depth;
    b = std::size_t(std::partition_point(cells.begin() + std::ptrdiff_t(b), cells.end(),
                                         [d](const auto& c) { return c.depth <= d; }) -
                    cells.begin());
  }
  out.push_back(std::uint32_t(cells.size()));
}

/// Calls f(c) for every cell, a level at a time from the deepest up, each level on the
/// threads: a pass that sets a cell from its children (which lie one level deeper).
template <class F>
void levels_up(const std::vector<std::uint32_t>& starts, F&& f) {
  for (std::size_t k = starts.size(); k-- > 1;)
    parallel_for_static(std::ptrdiff_t(starts[k] - starts[k - 1]),
                        [&](std::ptrdiff_t i) { f(std::size_t(starts[k - 1]) + std::size_t(i)); }, 1024);
}
}  // namespace detail

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
    shared_.reset();
  }

  /// Keeps each i-group's candidate list for the later walks of
  /// calcForceOnTreeAndWriteBack at the same positions (the passes of a smoothing-length
  /// iteration after refresh(), and, through buildLike(), the other kernels of the step),
  /// instead of walking the tree every time. The lists are collected in the symmetric
  /// mode with every search radius (i and j, EPI and EPJ) grown by the fraction
  /// `margin`: a superset of what any mode needs while no radius has grown past that
  /// (the kernels apply the exact cut, so they see extra candidates only as pairs out of
  /// reach). A walk checks that the positions are those of the collection (else a new,
  /// empty set) and that no radius outgrew its reach: a particle that did gets a new
  /// reach and the lists of the groups within it are collected again (more than a
  /// twentieth of the particles: a new set). The lists are filled lazily, by the first
  /// walk that needs each. The kernels get the same neighbours as without kept lists, in the same order,
  /// plus the out-of-reach candidates: sums over neighbours agree to rounding (exactly,
  /// where the kernel adds zero for those). margin < 0 turns it off (the default).
  void keepCandidates(double margin) {
    static_assert(HasRSearch<EPI> && HasRSearch<EPJ>,
                  "pik: kept candidate lists need `getRSearch()` on the EPI and EPJ types");
    if (!(margin < 0) && !(margin >= 0 && margin < 1))
      throw Error("keepCandidates: the margin must be in [0, 1) (or negative: off), got " + std::to_string(margin));
    keep_ = margin;
    shared_.reset();
  }
  /// Groups whose candidate lists were collected since the kept lists were last made
  /// anew, and how many times they were made (statistics of keepCandidates).
  std::uint64_t keptListsCollected() const { return shared_ ? shared_->collected : 0; }
  std::uint64_t keptListSets() const { return n_sets_; }

  /// Keeps the tree of the last build and takes the particles' new contents (h and
  /// search radii; positions too, if they moved): every particle is copied again and
  /// the cells' boxes and largest radii are recomputed, the topology (Morton order,
  /// cells, groups) is kept. A walk on a refreshed tree hands kernels exactly the
  /// neighbours a rebuilt tree would (the tests use the recomputed tight boxes); only
  /// its cost grows as particles drift away from the order they were sorted in. For
  /// the passes of a smoothing-length iteration (positions fixed, h changing) and for
  /// several kernels at the same positions. Same particles in the same order as the
  /// build (else an error). A tree built with imported particles takes their new
  /// contents from the vector last given to setImportedParticles, which must hold as
  /// many as the build had (e.g. wall images whose h follows their originals'). Profiled
  /// as "tree refresh".
  template <class FP>
  void refresh(const ParticleSystem<FP>& ps) {
    if (nodes_.empty() && ps.size() > 0) throw Error("refresh: the tree was never built");
    if (ps.size() != this->n_local_ || this->epj_.size() != this->n_local_ + this->imported_epj_.size())
      throw Error("refresh needs the particles of the last build (had " + std::to_string(this->n_local_) +
                  " local and " + std::to_string(this->epj_.size() - this->n_local_) + " imported, now " +
                  std::to_string(ps.size()) + " and " + std::to_string(this->imported_epj_.size()) + ")");
    reload_contents(ps);
  }

  /// refresh() for a pass in which only the particles with changed[i] != 0 (i: the
  /// particle-system index) changed, and not their positions (a smoothing-length
  /// iteration: new h for the unconverged particles): only those are copied again and,
  /// where the mode reads the j radii, the cells' largest radii recomputed; the cell
  /// boxes stay. The same tree as refresh(ps). A changed particle that moved is an error
  /// (refresh(ps) takes new positions); an empty span: refresh(ps).
  template <class FP>
  void refresh(const ParticleSystem<FP>& ps, std::span<const std::uint8_t> changed) {
    if (changed.empty()) return refresh(ps);
    if (nodes_.empty() && ps.size() > 0) throw Error("refresh: the tree was never built");
    if (ps.size() != this->n_local_ || changed.size() != ps.size() || this->epj_.size() != this->n_local_)
      throw Error("refresh of changed particles needs the " + std::to_string(this->n_local_) +
                  " particles of the last build, no imported ones, and a flag for each (got " +
                  std::to_string(ps.size()) + " particles, " + std::to_string(changed.size()) + " flags)");
    auto t = prof_.scope("tree refresh");
    const auto& loc = this->tree_.sorted(ItemKind::local);
    std::atomic<std::ptrdiff_t> moved{-1};
    detail::parallel_for_static(std::ptrdiff_t(this->n_local_), [&](std::ptrdiff_t i) {
      const std::size_t k = std::size_t(i);
      if (!changed[loc[k]]) return;
      const FP& fp = ps[loc[k]];
      this->epi_[k].copyFromFP(fp);
      this->epj_[k].copyFromFP(fp);
      if (!(detail::to_dvec<dim>(this->epj_[k].getPos()) == jrec_[k].x)) moved.store(std::ptrdiff_t(loc[k]));
      if constexpr (Mode != SearchMode::gather) jrec_[k].r = double(this->epj_[k].getRSearch());
    });
    if (moved.load() >= 0)
      throw Error("refresh of changed particles: particle " + std::to_string(moved.load()) +
                  " moved since the build (refresh(ps) takes new positions)");
    if constexpr (Mode != SearchMode::gather) {
      // the largest radius of every cell again (the boxes are those of the same positions)
      radii_up(nodes_, jrec_, levels_);
      detail::parallel_for_static(std::ptrdiff_t(nodes_.size()),
                                  [&](std::ptrdiff_t c) { rmax_[std::size_t(c)] = nodes_[std::size_t(c)].rmax; });
    }
    lists_kept_ = false;
  }

  /// Builds over `ps` with the topology of another short-range tree built over the same
  /// particles at the same positions (any force type and mode; e.g. a density tree
  /// lends its octree to the hydro-force tree of the same step): the Morton sort and
  /// the cell split are skipped, particles are copied and cell boxes and radii
  /// computed, so the result is that of build(ps). When the other tree holds imported
  /// particles, this one needs as many, at the same positions and in the same order,
  /// given by setImportedParticles (its own EPJ type: e.g. the same wall images).
  /// Profiled as "tree refresh".
  template <class Other, class FP>
  void buildLike(const Other& other, const ParticleSystem<FP>& ps) {
    const std::size_t n_imp = other.sortedEPJ().size() - std::min(other.sortedEPJ().size(), ps.size());
    if (other.numberOfLocalParticles() != ps.size() || other.sortedEPJ().size() < ps.size() ||
        this->imported_epj_.size() != n_imp ||
        other.octree().sorted(ItemKind::imported_particle).size() != n_imp)
      throw Error("buildLike: the other tree holds " + std::to_string(other.numberOfLocalParticles()) +
                  " local particles and " + std::to_string(n_imp) + " imported ones, this system " +
                  std::to_string(ps.size()) + " with " + std::to_string(this->imported_epj_.size()) +
                  " imported; both need the same particles and the same imports");
    {
      auto t = prof_.scope("tree refresh");
      this->tree_.assign_result(other.octree());
      this->groups_ = other.groups();
      this->n_local_ = ps.size();
      this->kind_.clear();
      this->epi_.resize(ps.size());
      this->epj_.resize(ps.size() + n_imp);
      this->force_.resize(ps.size());
      this->pos_.resize(ps.size());
      detail::parallel_for_static(std::ptrdiff_t(ps.size()),
                                  [&](std::ptrdiff_t i) { this->pos_[std::size_t(i)] = detail::to_dvec<dim>(ps[std::size_t(i)].getPos()); });
    }
    reload_contents(ps);
    check_inside_box(ps);
    // the other tree's kept lists, when both keep them with the same margin (same
    // octree, groups and positions; the walk checks the radii)
    shared_.reset();
    if constexpr (Other::dim == dim)
      if (keep_ >= 0 && other.keep_ == keep_) shared_ = other.shared_;
    adopted_ = bool(shared_);
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
      }, group_grain);
    if (keep_ >= 0) prepare_shared();
    walk(kernel, ListMode::rebuild, &group_on_, keep_ >= 0);
    // a set lent by buildLike is let go after the walk, so that its maker can reuse its
    // memory next step (a later walk of this tree at these positions makes its own)
    if (adopted_) shared_.reset(), adopted_ = false;
    auto t = prof_.scope("write back");
    detail::parallel_for_static(std::ptrdiff_t(groups.size()), [&](std::ptrdiff_t g) {
      if (!group_on_[std::size_t(g)]) return;
      for (std::uint32_t i = groups[std::size_t(g)].begin; i < groups[std::size_t(g)].end; ++i)
        ps[loc[i]].copyFromForce(this->force_[i]);
    }, group_grain);
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
    if (nodes_.empty()) return;
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
  template <class, class, class, SearchMode>
  friend class ShortRangeTree;
  /// Loops over i-groups (dozens of particles each) run on the threads from 64 groups on.
  static constexpr std::ptrdiff_t group_grain = 64;
  using Candidate = detail::SrCandidate;
  using Node = detail::SrNode<dim>;
  using JRec = detail::SrJRec<dim>;
  struct alignas(64) Scratch {
    std::vector<std::uint32_t> stack;
    std::vector<Candidate> cand;
    std::vector<dvec> shifts;
    std::vector<EPJ> epj;
    std::uint64_t n = 0;
    std::uint64_t collected = 0;
  };

  /// Copies every particle (and imported particle) again in the tree's order,
  /// recomputes the cell boxes and radii.
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
      // imported particles: their current contents, in the tree's order
      const auto& imp = this->tree_.sorted(ItemKind::imported_particle);
      const std::size_t nl = this->n_local_;
      for (std::size_t i = 0; i < imp.size(); ++i) {
        this->epj_[nl + i] = this->imported_epj_[imp[i] - nl];
        if (!isfinite(detail::to_dvec<dim>(this->epj_[nl + i].getPos())))
          throw Error(detail::describe_position<dim>("imported particle", imp[i] - nl,
                                                     detail::to_dvec<dim>(this->epj_[nl + i].getPos())));
      }
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
    const std::size_t nc = cells.size(), nl = this->n_local_, nj = this->epj_.size();
    // The j-particles' positions and search radii in double, in sortedEPJ() order: what
    // every candidate test reads (the same values as converting the EPJ on the fly).
    jrec_.resize(nj);
    detail::parallel_for_static(std::ptrdiff_t(nj), [&](std::ptrdiff_t j) {
      const EPJ& p = this->epj_[std::size_t(j)];
      JRec& q = jrec_[std::size_t(j)];
      q.x = detail::to_dvec<dim>(p.getPos());
      q.r = 0;
      if constexpr (Mode != SearchMode::gather) q.r = double(p.getRSearch());
    });
    boxes_.assign(nc, Box<double, dim>{});
    rmax_.assign(nc, 0.0);
    // the leaves on the threads (each from its own particles), then the other cells from
    // their children (children after their parent in the cell array)
    detail::parallel_for_static(std::ptrdiff_t(nc), [&](std::ptrdiff_t c) {
      const auto& cell = cells[std::size_t(c)];
      if (!cell.leaf()) return;
      Box<double, dim> box;
      double r = 0;
      auto add = [&](const JRec& q) {
        box.extend(q.x);
        if constexpr (Mode != SearchMode::gather) r = std::max(r, q.r);
      };
      for (std::uint32_t j = cell.kind_begin[0]; j < cell.kind_end[0]; ++j) add(jrec_[j]);
      for (std::uint32_t j = cell.kind_begin[1]; j < cell.kind_end[1]; ++j) add(jrec_[nl + j]);
      boxes_[std::size_t(c)] = box;
      rmax_[std::size_t(c)] = r;
    });
    // the cell array is breadth first: the levels from the deepest up, each on the threads
    detail::level_starts(cells, levels_);
    detail::levels_up(levels_, [&](std::size_t c) {
      const auto& cell = cells[c];
      if (cell.leaf()) return;
      Box<double, dim> box;
      double r = 0;
      for (std::uint32_t q = cell.child; q < cell.child + cell.n_child; ++q)
        box.extend(boxes_[q]), r = std::max(r, rmax_[q]);
      boxes_[c] = box;
      rmax_[c] = r;
    });
    nodes_.resize(nc);
    detail::parallel_for_static(std::ptrdiff_t(nc), [&](std::ptrdiff_t c) {
      const auto& cell = cells[std::size_t(c)];
      nodes_[std::size_t(c)] = {boxes_[std::size_t(c)], rmax_[std::size_t(c)], cell.child,        cell.n_child,
                                cell.kind_begin[0],     cell.kind_end[0],      cell.kind_begin[1], cell.kind_end[1]};
    });
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
  ///
  /// A cell that lies wholly within reach (gather and symmetric: the farthest point of
  /// its box is within ri of g) hands over all its particles without testing each: every
  /// one of them would pass its own test, since that test's distance, computed in the
  /// same double operations, cannot exceed the box's farthest one (rounding is monotone;
  /// the test keeps a margin of 1e-9) and its radius is never below ri. The candidates are those of the per-particle test
  /// in the same order (cells in depth-first order, a leaf's local then imported
  /// particles), so kernels see the same lists as before, bit for bit.
  void collect(const Box<double, dim>& g, double ri, std::vector<std::uint32_t>& stack,
               std::vector<dvec>& shifts, std::vector<Candidate>& cand) const {
    collect_in<Mode>(nodes_.data(), jrec_.data(), g, ri, stack, shifts, cand);
  }
  /// collect() in mode M over the given cells and j records (the tree's own, or the
  /// reaches of kept lists).
  template <SearchMode M>
  void collect_in(const Node* nodes, const JRec* jr, const Box<double, dim>& g, double ri,
                  std::vector<std::uint32_t>& stack, std::vector<dvec>& shifts, std::vector<Candidate>& cand) const {
    // Slack for rounding in box distances; the exact cut is applied by the caller.
    constexpr double slack = 1 + 1e-12;
    const std::size_t nl = this->n_local_;
    double reach = ri;
    if constexpr (M != SearchMode::gather) reach = std::max(ri, nodes[0].rmax);
    cand.clear();
    image_shifts(g.grown(reach * slack), shifts);
    const double ri2 = ri * ri * slack;
    // squared reach of a cell (the prune test): by the mode, from ri and its largest r_j
    auto cell_r2 = [&](const Node& nd) {
      if constexpr (M == SearchMode::scatter) return nd.rmax * nd.rmax * slack;
      if constexpr (M == SearchMode::symmetric) {
        const double r = std::max(ri, nd.rmax);
        return r * r * slack;
      }
      return ri2;
    };
    // One image of the tree; `shifted` std::false_type for the zero shift (open space has
    // only that one): the same tests without adding it (x + 0 is x: the same candidates).
    auto walk_image = [&](std::uint32_t s, auto shifted) {
      constexpr bool add = decltype(shifted)::value;
      const dvec& sh = shifts[s];
      auto img = [&](const dvec& x) -> dvec {
        if constexpr (add) return x + sh;
        return x;
      };
      auto in_reach = [&](const Node& nd) {
        Box<double, dim> b = nd.box;
        b.lo = img(b.lo), b.hi = img(b.hi);
        return g.distance2(b) <= cell_r2(nd);
      };
      stack.clear();
      // Cells are tested before they are pushed (children in reverse, so that they are
      // popped in order): the stack holds only cells within reach.
      if (in_reach(nodes[0])) stack.push_back(0);
      while (!stack.empty()) {
        const Node& nd = nodes[stack.back()];
        stack.pop_back();
        if constexpr (M != SearchMode::scatter) {
          // the farthest point of the cell's box from g, per dimension as Box::distance2
          // measures a point's distance
          double far2 = 0;
          const dvec lo = img(nd.box.lo), hi = img(nd.box.hi);
          for (int d = 0; d < dim; ++d) {
            const double e = std::max({0.0, g.lo[d] - lo[d], hi[d] - g.hi[d]});
            far2 += e * e;
          }
          // (a relative margin of 1e-9 covers the few ulps by which the two distances'
          // roundings may differ, e.g. where the compiler fuses a multiply-add in one)
          if (far2 * (1 + 1e-9) <= ri2 && (nd.n_child == 0 || nd.ie == nd.ib)) {
            // leaf, or a cell of local particles only: its range in depth-first order
            Candidate* out = grow(cand, (nd.le - nd.lb) + (nd.ie - nd.ib));
            for (std::uint32_t j = nd.lb; j < nd.le; ++j) *out++ = {j, s};
            for (std::uint32_t j = nd.ib; j < nd.ie; ++j) *out++ = {std::uint32_t(nl + j), s};
            continue;
          }
        }
        if (nd.n_child == 0) {
          // Every particle of the leaf is written and the count advances by the test's
          // outcome: no branch on it (near the reach half of them pass, which a predictor
          // cannot learn), the same candidates in the same order.
          const std::size_t n0 = cand.size();
          Candidate* const out = grow(cand, (nd.le - nd.lb) + (nd.ie - nd.ib));
          std::size_t k = 0;
          auto test = [&](std::uint32_t j) {
            double rj2 = ri2;
            if constexpr (M == SearchMode::scatter) rj2 = jr[j].r * jr[j].r * slack;
            if constexpr (M == SearchMode::symmetric) {
              const double rj = std::max(ri, jr[j].r);
              rj2 = rj * rj * slack;
            }
            out[k] = {j, s};
            k += std::size_t(g.distance2(img(jr[j].x)) <= rj2);
          };
          for (std::uint32_t j = nd.lb; j < nd.le; ++j) test(j);
          for (std::uint32_t j = nd.ib; j < nd.ie; ++j) test(std::uint32_t(nl + j));
          cand.resize(n0 + k);
        } else {
          for (std::uint32_t k = nd.n_child; k-- > 0;)
            if (in_reach(nodes[nd.child + k])) stack.push_back(nd.child + k);
        }
      }
    };
    for (std::uint32_t s = 0; s < shifts.size(); ++s) {
      if (is_zero(shifts[s])) walk_image(s, std::false_type{});
      else walk_image(s, std::true_type{});
    }
  }

  /// Appends n slots to v (their values to be written) and returns the first.
  static Candidate* grow(std::vector<Candidate>& v, std::size_t n) {
    v.resize(v.size() + n);
    return v.data() + (v.size() - n);
  }

  static bool is_zero(const dvec& sh) {
    bool zero = true;
    for (int d = 0; d < dim; ++d) zero = zero && sh[d] == 0;
    return zero;
  }

  EPJ shifted(const EPJ& p, const dvec& sh) const {
    if constexpr (HasSetPos<EPJ>) {
      if (is_zero(sh)) return p;
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

  /// Makes the kept lists valid for the present positions and radii (keepCandidates).
  /// Same positions as their collection: a particle whose radius outgrew its reach gets
  /// a new reach, and the lists of the groups within it are dropped (collected again
  /// when walked); if more than a twentieth did, or a position changed, a new, empty set
  /// starts with reaches from the present radii.
  void prepare_shared() {
    const std::size_t nl = this->n_local_, nj = this->epj_.size();
    const auto& groups = this->groups_;
    auto radius = [&](std::size_t j) {
      double r = double(this->epj_[j].getRSearch());
      if (j < nl) r = std::max(r, double(this->epi_[j].getRSearch()));
      return r;
    };
    if (shared_ && shared_->margin == keep_ && shared_->jrec.size() == nj && shared_->cj.size() == groups.size()) {
      auto& S = *shared_;
      // On the threads, in blocks (each block's grown particles in its own list, kept
      // between calls); a block stops at a moved particle, which ends the check.
      const std::size_t nb = std::min<std::size_t>(64, std::max<std::size_t>(1, nj / 4096));
      grown_in_.resize(nb);
      std::atomic<bool> moved{false};
      detail::parallel_for(std::ptrdiff_t(nb), [&](std::ptrdiff_t b, int) {
        auto& out = grown_in_[std::size_t(b)];
        out.clear();
        for (std::size_t j = nj * std::size_t(b) / nb, e = nj * (std::size_t(b) + 1) / nb; j < e; ++j) {
          if (!(S.jrec[j].x == jrec_[j].x)) {
            moved.store(true, std::memory_order_relaxed);
            return;
          }
          if (radius(j) > S.jrec[j].r) out.push_back(std::uint32_t(j));
        }
      });
      const bool same = !moved.load();
      std::size_t n_grown = 0;
      for (std::size_t b = 0; b < nb; ++b) n_grown += grown_in_[b].size();
      if (same && n_grown == 0) return;
      if (same && n_grown <= nj / 20) {
        std::vector<std::uint32_t> grown;
        grown.reserve(n_grown);
        for (std::size_t b = 0; b < nb; ++b) grown.insert(grown.end(), grown_in_[b].begin(), grown_in_[b].end());
        for (std::uint32_t j : grown) S.jrec[j].r = radius(j) * (1 + keep_);
        set_reaches(S);
        // A group keeps its list unless one of its particles lies within a grown reach
        // (any periodic image). Such a list still holds every pair a walk needs: a pair
        // (i, j) with |x_i - x_j| <= max(r_i, r_j) is in it when r_i <= reach_i (unchanged
        // for i not grown; a grown i marks its own group) or, where only r_j grew, i lies
        // within j's new reach and so marks the group. The search starts from the grown
        // particles, through the set's cells: O(grown log N), not O(grown x groups).
        hit_.assign(nl, 0);
        scratch_.resize(std::size_t(detail::max_threads()));  // the walk's per-thread stacks
        detail::parallel_for(std::ptrdiff_t(grown.size()), [&](std::ptrdiff_t k, int thread) {
          Scratch& t = scratch_[std::size_t(thread)];
          mark_within(S, grown[std::size_t(k)], t.stack, t.shifts, hit_);
        }, 64);
        detail::parallel_for_static(std::ptrdiff_t(groups.size()), [&](std::ptrdiff_t g) {
          if (!S.have[std::size_t(g)]) return;
          for (std::uint32_t i = groups[std::size_t(g)].begin; i < groups[std::size_t(g)].end; ++i)
            if (hit_[i]) {
              S.have[std::size_t(g)] = 0;
              return;
            }
        }, group_grain);
        return;
      }
    }
    adopted_ = false;
    auto S = recycled_set();
    S->margin = keep_;
    S->jrec.resize(nj);
    detail::parallel_for_static(std::ptrdiff_t(nj), [&](std::ptrdiff_t j) {
      S->jrec[std::size_t(j)] = {jrec_[std::size_t(j)].x, radius(std::size_t(j)) * (1 + keep_)};
    });
    S->nodes = nodes_;
    S->levels = levels_;
    set_reaches(*S);
    S->gbox.resize(groups.size());
    S->cj.resize(groups.size());
    S->cs.resize(groups.size());
    S->shifts.resize(groups.size());
    S->have.resize(groups.size());
    detail::parallel_for_static(std::ptrdiff_t(groups.size()), [&](std::ptrdiff_t g) {
      Box<double, dim> b;
      for (std::uint32_t i = groups[std::size_t(g)].begin; i < groups[std::size_t(g)].end; ++i) b.extend(jrec_[i].x);
      S->gbox[std::size_t(g)] = b;
      S->cj[std::size_t(g)].clear(), S->cs[std::size_t(g)].clear(), S->shifts[std::size_t(g)].clear();
      S->have[std::size_t(g)] = 0;
    }, group_grain);
    S->collected = 0;
    shared_ = std::move(S);
    ++n_sets_;
  }

  /// Marks in hit the local particles within the reach of set particle j, at any
  /// periodic image (the query walks the set's cells, whose boxes hold the positions of
  /// the collection; a cell wholly within reach marks its range without a test each).
  void mark_within(const detail::SharedCandidates<dim>& S, std::uint32_t j, std::vector<std::uint32_t>& stack,
                   std::vector<dvec>& shifts, std::vector<std::uint8_t>& hit) const {
    constexpr double slack = 1 + 1e-12;
    const dvec x = S.jrec[j].x;
    const double r2 = S.jrec[j].r * S.jrec[j].r * slack;
    Box<double, dim> q;
    q.extend(x);
    image_shifts(q.grown(S.jrec[j].r * slack), shifts);
    auto mark = [&](std::uint32_t i) { std::atomic_ref<std::uint8_t>(hit[i]).store(1, std::memory_order_relaxed); };
    for (const dvec& sh : shifts) {
      stack.assign(1, 0);
      while (!stack.empty()) {
        const Node& nd = S.nodes[stack.back()];
        stack.pop_back();
        if (nd.le == nd.lb && nd.n_child == 0) continue;  // no local particle
        Box<double, dim> b = nd.box;
        b.lo += sh, b.hi += sh;
        if (b.distance2(x) > r2) continue;
        double far2 = 0;  // the box's farthest point from x
        for (int d = 0; d < dim; ++d) {
          const double e = std::max(x[d] - b.lo[d], b.hi[d] - x[d]);
          far2 += e * e;
        }
        if (far2 <= r2 * (1 - 1e-9) && (nd.n_child == 0 || nd.ie == nd.ib)) {
          for (std::uint32_t i = nd.lb; i < nd.le; ++i) mark(i);
          continue;
        }
        if (nd.n_child == 0) {
          for (std::uint32_t i = nd.lb; i < nd.le; ++i)
            if (norm2(S.jrec[i].x + sh - x) <= r2) mark(i);
        } else {
          for (std::uint32_t k = 0; k < nd.n_child; ++k) stack.push_back(nd.child + k);
        }
      }
    }
  }

  /// An empty set for prepare_shared: one this tree made before and nobody else holds any
  /// more (its lists' memory is reused: a set per step would otherwise allocate and touch
  /// tens of MB of fresh pages every step), or a new one. The ring keeps the last three.
  std::shared_ptr<detail::SharedCandidates<dim>> recycled_set() {
    shared_.reset();
    for (auto& r : recycle_)
      if (r && r.use_count() == 1) return r;
    auto S = std::make_shared<detail::SharedCandidates<dim>>();
    auto* slot = &recycle_[0];
    for (auto& r : recycle_)
      if (!r) {
        slot = &r;
        break;
      }
    if (*slot) {  // every slot in use elsewhere: the oldest leaves the ring
      std::rotate(recycle_.begin(), recycle_.begin() + 1, recycle_.end());
      slot = &recycle_.back();
    }
    *slot = S;
    return S;
  }

  /// The cells' largest reach of a kept-list set.
  void set_reaches(detail::SharedCandidates<dim>& S) const { radii_up(S.nodes, S.jrec, S.levels); }

  /// Every cell's rmax from the j records' radii: the leaves from their particles (local,
  /// then imported) on the threads, the other cells from their children a level at a time
  /// (`levels`: level_starts of the same cells).
  void radii_up(std::vector<Node>& nodes, const std::vector<JRec>& jr, const std::vector<std::uint32_t>& levels) const {
    const std::size_t nl = this->n_local_;
    detail::parallel_for_static(std::ptrdiff_t(nodes.size()), [&](std::ptrdiff_t c) {
      Node& nd = nodes[std::size_t(c)];
      if (nd.n_child != 0) return;
      double r = 0;
      for (std::uint32_t j = nd.lb; j < nd.le; ++j) r = std::max(r, jr[j].r);
      for (std::uint32_t j = nd.ib; j < nd.ie; ++j) r = std::max(r, jr[nl + j].r);
      nd.rmax = r;
    });
    detail::levels_up(levels, [&](std::size_t c) {
      Node& nd = nodes[c];
      if (nd.n_child == 0) return;
      double r = 0;
      for (std::uint32_t k = nd.child; k < nd.child + nd.n_child; ++k) r = std::max(r, nodes[k].rmax);
      nd.rmax = r;
    });
  }

  template <class K>
  void walk(K& kernel, ListMode lm, const std::vector<unsigned char>* group_on = nullptr, bool kept = false) {
    auto t = prof_.scope("walk+kernel");
    const auto& groups = this->groups_;
    scratch_.resize(std::size_t(detail::max_threads()));
    for (Scratch& s : scratch_) s.n = 0, s.collected = 0;
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
      // the candidates (j index and image shift index of each, by accessor) copied into
      // the thread's buffer, then the kernel
      auto call = [&](std::size_t nc, auto j_of, auto shift_of, const std::vector<dvec>& sh) {
        if (s.epj.size() < nc) s.epj.resize(nc + nc / 4);  // only grows (no per-candidate push_back)
        EPJ* out = s.epj.data();
        const EPJ* src = this->epj_.data();
        if (sh.size() == 1 && is_zero(sh[0])) {
          for (std::size_t k = 0; k < nc; ++k) out[k] = src[j_of(k)];
        } else {
          for (std::size_t k = 0; k < nc; ++k) out[k] = shifted(src[j_of(k)], sh[shift_of(k)]);
        }
        Force* f = this->force_.data() + ib;
        const int ni = int(ie - ib);
        for (int i = 0; i < ni; ++i) f[i].clear();
        if (nc > 0) kernel(this->epi_.data() + ib, ni, s.epj.data(), int(nc), f);
        s.n += std::uint64_t(ni) * nc;
      };
      if (kept) {
        // the kept list, collected now if no walk has needed it yet
        auto& S = *shared_;
        auto& cj = S.cj[std::size_t(g)];
        auto& cs = S.cs[std::size_t(g)];
        const auto& sh = S.shifts[std::size_t(g)];
        if (!S.have[std::size_t(g)]) {
          double ri = 0;
          for (std::uint32_t i = ib; i < ie; ++i) ri = std::max(ri, S.jrec[i].r);
          collect_in<SearchMode::symmetric>(S.nodes.data(), S.jrec.data(), S.gbox[std::size_t(g)], ri, s.stack,
                                            S.shifts[std::size_t(g)], s.cand);
          cj.resize(s.cand.size());
          for (std::size_t k = 0; k < s.cand.size(); ++k) cj[k] = s.cand[k].j;
          cs.clear();
          if (sh.size() > 1) {
            cs.resize(s.cand.size());
            for (std::size_t k = 0; k < s.cand.size(); ++k) cs[k] = s.cand[k].shift;
          }
          S.have[std::size_t(g)] = 1;
          ++s.collected;
        }
        auto j_of = [&](std::size_t k) { return cj[k]; };
        if (cs.empty()) call(cj.size(), j_of, [](std::size_t) { return std::uint32_t(0); }, sh);
        else call(cj.size(), j_of, [&](std::size_t k) { return cs[k]; }, sh);
        return;
      }
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
      const Candidate* c = cand->data();
      call(cand->size(), [c](std::size_t k) { return c[k].j; }, [c](std::size_t k) { return c[k].shift; }, *shifts);
    });
    n_int_ = 0;
    for (const Scratch& s : scratch_) n_int_ += s.n;
    if (kept)
      for (const Scratch& s : scratch_) shared_->collected += s.collected;
  }

  struct Kept {
    std::vector<Candidate> cand;
    std::vector<dvec> shifts;
  };

  TreeParams params_;
  Boundary<dim> boundary_;
  Profiler prof_;
  std::vector<Box<double, dim>> boxes_;
  std::vector<double> rmax_;
  std::vector<std::uint32_t> levels_;  ///< level starts of the cell array (compute_cells)
  std::vector<std::vector<std::uint32_t>> grown_in_;  ///< prepare_shared's per-block grown particles
  std::vector<JRec> jrec_;
  std::vector<Node> nodes_;
  std::vector<Scratch> scratch_;
  std::vector<Kept> kept_;
  bool lists_kept_ = false;
  double keep_ = -1;  ///< keepCandidates' margin (< 0: off)
  std::shared_ptr<detail::SharedCandidates<dim>> shared_;
  std::array<std::shared_ptr<detail::SharedCandidates<dim>>, 3> recycle_;
  bool adopted_ = false;  ///< shared_ came from another tree (buildLike)
  std::uint64_t n_sets_ = 0;
  std::uint64_t n_int_ = 0;
  std::vector<unsigned char> group_on_;
  std::size_t n_groups_walked_ = 0;
  std::vector<std::uint8_t> hit_;  ///< prepare_shared: local particles within a grown reach
};

}  // namespace pik
