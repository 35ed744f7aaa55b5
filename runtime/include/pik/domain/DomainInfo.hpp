/// \file DomainInfo.hpp
/// \brief pik::DomainInfo: multisection domain decomposition weighted by measured cost.
///
/// The ranks form an nx × ny × nz grid (chosen from the rank count, or given). Each
/// decompose() call samples the local particles, with a number of samples
/// proportional to the rank's measured cost of the last step, and every sample
/// weighted by the cost it stands for; rank 0 cuts the gathered samples into cells
/// of equal weight (domain_detail::multisect) and broadcasts the cuts. A rank that
/// was slow therefore gets a smaller domain and fewer particles. Cuts are smoothed
/// over steps by an exponential moving average (Options::smoothing), which damps
/// the sampling noise that would otherwise move particles back and forth.
///
/// The root domain is open (outer cuts at ±infinity: every position has an owner)
/// or periodic per dimension in a given box [lo, hi) (positions are wrapped).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <ranges>
#include <span>
#include <string>
#include <vector>

#include "pik/comm/Comm.hpp"
#include "pik/domain/DomainBox.hpp"
#include "pik/domain/Position.hpp"
#include "pik/domain/ProcessGrid.hpp"
#include "pik/domain/detail/Multisection.hpp"

namespace pik {

template <class Real = double, int Dim = 3, class CommT = Comm>
class DomainInfo {
  static_assert(std::is_floating_point_v<Real>, "DomainInfo: Real must be floating point");
  static_assert(Dim >= 1 && Dim <= 3, "DomainInfo: Dim must be 1, 2 or 3");

 public:
  using Box = DomainBox<Real, Dim>;
  using Point = std::array<Real, Dim>;

  struct Options {
    /// Ranks along each dimension; all zero = choose_process_grid(size).
    std::array<int, Dim> grid{};
    /// Average number of samples per rank (total = this × ranks); more samples,
    /// finer balance (relative noise about 1/sqrt(samples per domain)).
    int samples_per_rank = 1000;
    /// Weight of the new cuts in the moving average of cuts over steps, in (0, 1];
    /// 1 = no smoothing. The first decomposition is never smoothed.
    double smoothing = 1.0;
    /// Seed of the sampling; the same seed gives the same decompositions.
    std::uint64_t seed = 0x9e3779b97f4a7c15ull;
  };

  explicit DomainInfo(CommT comm) : DomainInfo(std::move(comm), Options{}) {}
  DomainInfo(CommT comm, Options opt) : comm_(std::move(comm)), opt_(opt) {
    const bool automatic = std::all_of(opt_.grid.begin(), opt_.grid.end(), [](int n) { return n == 0; });
    if (automatic) opt_.grid = choose_process_grid<Dim>(comm_.size());
    long prod = 1;
    for (int n : opt_.grid) prod *= n;
    if (prod != comm_.size() || std::any_of(opt_.grid.begin(), opt_.grid.end(), [](int n) { return n < 1; })) {
      std::string g;
      for (int d = 0; d < Dim; ++d) g += (d ? " x " : "") + std::to_string(opt_.grid[d]);
      comm_.abort("DomainInfo: rank grid " + g + " does not multiply to the " +
                  std::to_string(comm_.size()) + " ranks");
    }
    if (!(opt_.smoothing > 0 && opt_.smoothing <= 1))
      comm_.abort("DomainInfo: smoothing must be in (0, 1], got " + std::to_string(opt_.smoothing));
    if (opt_.samples_per_rank < 1)
      comm_.abort("DomainInfo: samples_per_rank must be positive");
    for (int d = 0; d < Dim; ++d) {
      root_.lo[d] = -std::numeric_limits<Real>::infinity();
      root_.hi[d] = std::numeric_limits<Real>::infinity();
    }
    reset_cuts();
  }

  /// Makes dimension d periodic in [box.lo[d], box.hi[d]) where periodic[d];
  /// other dimensions stay open. Resets the decomposition.
  void set_root_domain(const Box& box, std::array<bool, Dim> periodic) {
    for (int d = 0; d < Dim; ++d) {
      periodic_[d] = periodic[d];
      if (periodic[d]) {
        if (!(std::isfinite(box.lo[d]) && std::isfinite(box.hi[d]) && box.lo[d] < box.hi[d]))
          comm_.abort("DomainInfo: periodic dimension " + std::to_string(d) +
                      " needs a finite box with lo < hi");
        root_.lo[d] = box.lo[d];
        root_.hi[d] = box.hi[d];
      } else {
        root_.lo[d] = -std::numeric_limits<Real>::infinity();
        root_.hi[d] = std::numeric_limits<Real>::infinity();
      }
    }
    reset_cuts();
  }
  /// From a boundary description with `box.lo/hi` and `periodic[d]` flags
  /// (pik::Boundary<D>).
  template <class B>
    requires requires(const B& b) {
      b.box.lo;
      b.box.hi;
      b.periodic[0];
    }
  void set_root_domain(const B& b) {
    Box box;
    std::array<bool, Dim> per{};
    for (int d = 0; d < Dim; ++d) {
      box.lo[d] = static_cast<Real>(domain_detail::coord(b.box.lo, d));
      box.hi[d] = static_cast<Real>(domain_detail::coord(b.box.hi, d));
      per[d] = b.periodic[d];
    }
    set_root_domain(box, per);
  }
  /// Fully periodic box.
  void set_periodic_box(const Box& box) {
    std::array<bool, Dim> all;
    all.fill(true);
    set_root_domain(box, all);
  }

  /// Recomputes the domains from the particles now on this rank. `cost` is this
  /// rank's measured work of the last step (e.g. seconds of force calculation);
  /// negative or non-finite = the local particle count (equal cost per particle).
  /// Collective.
  template <std::ranges::random_access_range Particles>
    requires HasPosition<std::ranges::range_value_t<Particles>>
  void decompose(const Particles& particles, double cost = -1.0) {
    const auto n = static_cast<std::uint64_t>(std::ranges::size(particles));
    double c = (cost >= 0 && std::isfinite(cost)) ? cost : static_cast<double>(n);
    const std::uint64_t n_total = comm_.sum(n);
    double c_total = comm_.sum(c);
    if (n_total == 0) return;  // nothing to balance; keep the current domains
    if (!(c_total > 0) || !std::isfinite(c_total)) {
      c = static_cast<double>(n);
      c_total = static_cast<double>(n_total);
    }
    // Samples in proportion to cost, each standing for an equal share of it; a
    // rank with fewer particles than its share sends all, weighted up.
    const double wanted = double(opt_.samples_per_rank) * comm_.size() * c / c_total;
    std::uint64_t ns = 0;
    if (n > 0 && c > 0) ns = std::clamp<std::uint64_t>(std::llround(wanted), 1, n);
    std::vector<Sample> mine;
    mine.reserve(ns);
    std::mt19937_64 rng(opt_.seed ^ (0x100000001b3ull * (std::uint64_t(comm_.rank()) + 1)) ^
                        (std::uint64_t(decompositions_) << 32));
    std::uniform_real_distribution<double> u(0.0, 1.0);
    const double w = ns ? c / double(ns) : 0.0;
    for (std::uint64_t k = 0; k < ns; ++k) {
      // Stratified: one sample per stretch of n/ns particles; particles sorted in
      // space (Morton order) give spatially stratified samples.
      auto i = static_cast<std::uint64_t>((double(k) + u(rng)) * double(n) / double(ns));
      i = std::min(i, n - 1);
      Sample s{point_of(domain_detail::position(particles[static_cast<std::size_t>(i)])), w};
      bool finite = true;
      for (int d = 0; d < Dim; ++d) finite = finite && std::isfinite(s.x[d]);
      if (finite) mine.push_back(s);
    }
    auto all = comm_.gatherv(std::span<const Sample>(mine), 0);
    std::vector<Real> flat;
    if (comm_.is_root()) {
      Cuts fresh;
      fresh.resize(opt_.grid);
      domain_detail::multisect<Real, Dim>(std::span<Sample>(all), fresh, 0, 0, root_.lo, root_.hi);
      if (decompositions_ > 0 && opt_.smoothing < 1) {
        for (int d = 0; d < Dim; ++d) {
          auto& nw = fresh.level[d];
          const auto& old = cuts_.level[d];
          const std::size_t per = static_cast<std::size_t>(opt_.grid[d] + 1);
          for (std::size_t i = 0; i < nw.size(); ++i) {
            if (i % per == 0 || i % per == per - 1) continue;  // outer cuts are fixed
            nw[i] = Real(opt_.smoothing * nw[i] + (1 - opt_.smoothing) * old[i]);
          }
        }
      }
      cuts_ = std::move(fresh);
    }
    for (int d = 0; d < Dim; ++d) comm_.broadcast(std::span<Real>(cuts_.level[d]), 0);
    ++decompositions_;
  }

  /// Wraps `pos` into the periodic box (open dimensions untouched); returns
  /// whether it changed.
  template <class V>
  bool wrap(V& pos) const {
    bool changed = false;
    for (int d = 0; d < Dim; ++d) {
      if (!periodic_[d]) continue;
      const Real x = static_cast<Real>(domain_detail::coord(pos, d));
      const Real y = wrap_coord(x, d);
      if (y != x) {
        domain_detail::set_coord(pos, d, y);
        changed = true;
      }
    }
    return changed;
  }

  /// The rank owning `pos` (wrapped into the periodic box first). Every finite
  /// position has exactly one owner.
  template <class V>
  int owner(const V& pos) const {
    Point p = point_of(pos);
    std::size_t cell = 0;
    for (int d = 0; d < Dim; ++d) {
      const int n = opt_.grid[d];
      const Real* c = cuts_.cuts(d, cell);
      int k = static_cast<int>(std::upper_bound(c, c + n + 1, p[d]) - c) - 1;
      k = std::clamp(k, 0, n - 1);
      cell = cell * static_cast<std::size_t>(n) + static_cast<std::size_t>(k);
    }
    return static_cast<int>(cell);
  }

  /// The box [lo, hi) that `rank` owns (infinite sides at open outer faces).
  Box domain(int rank) const {
    std::array<int, Dim> idx{};
    int r = rank;
    for (int d = Dim - 1; d >= 0; --d) {
      idx[d] = r % opt_.grid[d];
      r /= opt_.grid[d];
    }
    Box b;
    std::size_t cell = 0;
    for (int d = 0; d < Dim; ++d) {
      const Real* c = cuts_.cuts(d, cell);
      b.lo[d] = c[idx[d]];
      b.hi[d] = c[idx[d] + 1];
      cell = cell * static_cast<std::size_t>(opt_.grid[d]) + static_cast<std::size_t>(idx[d]);
    }
    return b;
  }

  const std::array<int, Dim>& grid() const { return opt_.grid; }
  const Box& root_domain() const { return root_; }
  bool periodic(int d) const { return periodic_[d]; }
  const CommT& comm() const { return comm_; }
  const Options& options() const { return opt_; }
  /// Number of decompose() calls that balanced particles so far.
  int decompositions() const { return decompositions_; }

  /// The decomposition state as numbers, exactly: the decomposition count (it seeds
  /// the sampling) followed by every cut (the smoothing starts from them). A
  /// checkpoint that stores it and restore_state() at the same rank grid make the
  /// decompositions after a restart the same, bit for bit, as in an uninterrupted
  /// run, provided each rank gets back its particles in the same order and cost.
  std::vector<double> state() const {
    std::vector<double> s{double(decompositions_)};
    for (int d = 0; d < Dim; ++d) s.insert(s.end(), cuts_.level[d].begin(), cuts_.level[d].end());
    return s;
  }
  /// Restores state() of a DomainInfo with the same grid; collective only in that
  /// every rank must call it with the same numbers. Stops the program on a state of
  /// the wrong size (another grid or dimension).
  void restore_state(std::span<const double> s) {
    std::size_t want = 1;
    for (int d = 0; d < Dim; ++d) want += cuts_.level[d].size();
    if (s.size() != want || !(s[0] >= 0) || s[0] != std::floor(s[0]))
      comm_.abort("DomainInfo: a saved decomposition state of " + std::to_string(s.size()) +
                  " numbers does not fit this rank grid (" + std::to_string(want) + " expected)");
    decompositions_ = int(s[0]);
    std::size_t k = 1;
    for (int d = 0; d < Dim; ++d)
      for (auto& c : cuts_.level[d]) c = Real(s[k++]);
  }

 private:
  using Sample = domain_detail::Sample<Real, Dim>;
  using Cuts = domain_detail::Cuts<Real, Dim>;

  /// Before the first decomposition rank 0 owns all space (every other domain is
  /// empty), so owner() is valid at any time.
  void reset_cuts() {
    cuts_.resize(opt_.grid);
    for (int d = 0; d < Dim; ++d) {
      const std::size_t per = static_cast<std::size_t>(opt_.grid[d] + 1);
      for (std::size_t i = 0; i < cuts_.level[d].size(); ++i)
        cuts_.level[d][i] = (i % per == 0) ? root_.lo[d] : root_.hi[d];
    }
    decompositions_ = 0;
  }

  Real wrap_coord(Real x, int d) const {
    const Real lo = root_.lo[d], hi = root_.hi[d];
    if (x >= lo && x < hi) return x;
    if (!std::isfinite(x)) return x;
    const Real w = hi - lo;
    Real y = x - w * std::floor((x - lo) / w);
    // Rounding can land exactly on hi or just below lo.
    if (y >= hi) y -= w;
    if (y < lo) y = lo;
    return y;
  }

  template <class V>
  Point point_of(const V& v) const {
    Point p;
    for (int d = 0; d < Dim; ++d) {
      p[d] = static_cast<Real>(domain_detail::coord(v, d));
      if (periodic_[d]) p[d] = wrap_coord(p[d], d);
    }
    return p;
  }

  CommT comm_;
  Options opt_;
  Box root_{};
  std::array<bool, Dim> periodic_{};
  Cuts cuts_;
  int decompositions_ = 0;
};

}  // namespace pik
