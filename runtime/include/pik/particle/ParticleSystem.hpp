/// \file ParticleSystem.hpp
/// \brief The particles of one process: a growable array of the user's particle class.
///
/// Plain contiguous storage (FDPS's ParticleSystem without the MPI parts). The
/// distributed layer (domain decomposition, particle exchange) works through the
/// public members here: it reads particles, removes those that leave and appends
/// those that arrive.
#pragma once

#include <algorithm>
#include <atomic>
#include <cstdint>
#include <span>
#include <sstream>
#include <vector>

#include "pik/Boundary.hpp"
#include "pik/Error.hpp"
#include "pik/detail/Threads.hpp"
#include "pik/particle/Concepts.hpp"
#include "pik/tree/MortonKey.hpp"

namespace pik {

template <class FP>
class ParticleSystem {
  static_assert(HasPos<FP>,
                "pik: the full particle type needs `getPos()` returning its position vector");

 public:
  using value_type = FP;
  static constexpr int dim = dim_of<FP>;

  ParticleSystem() = default;
  explicit ParticleSystem(std::vector<FP> p) : p_(std::move(p)) {}

  std::size_t size() const { return p_.size(); }
  bool empty() const { return p_.empty(); }
  FP& operator[](std::size_t i) { return p_[i]; }
  const FP& operator[](std::size_t i) const { return p_[i]; }
  FP* data() { return p_.data(); }
  const FP* data() const { return p_.data(); }
  auto begin() { return p_.begin(); }
  auto end() { return p_.end(); }
  auto begin() const { return p_.begin(); }
  auto end() const { return p_.end(); }
  std::vector<FP>& vector() { return p_; }
  const std::vector<FP>& vector() const { return p_; }

  void add(const FP& p) { p_.push_back(p); }
  void add(std::span<const FP> ps) { p_.insert(p_.end(), ps.begin(), ps.end()); }
  void resize(std::size_t n) { p_.resize(n); }
  void reserve(std::size_t n) { p_.reserve(n); }
  void clear() { p_.clear(); }

  /// Removes the particles at the given indices (any order, repeats allowed); the
  /// others keep their relative order.
  void remove(std::span<const std::size_t> indices) {
    std::vector<char> gone(p_.size(), 0);
    for (std::size_t i : indices) {
      if (i >= p_.size())
        throw Error("remove: index " + std::to_string(i) + " out of range (size " +
                    std::to_string(p_.size()) + ")");
      gone[i] = 1;
    }
    std::size_t k = 0;
    for (std::size_t i = 0; i < p_.size(); ++i)
      if (!gone[i]) {
        if (k != i) p_[k] = std::move(p_[i]);
        ++k;
      }
    p_.resize(k);
  }
  /// Removes every particle for which pred(p) is true; the others keep their order.
  template <class Pred>
  void remove_if(Pred pred) {
    p_.erase(std::remove_if(p_.begin(), p_.end(), pred), p_.end());
  }

  /// Stable sort by a comparator.
  template <class Less>
  void sort(Less less) {
    std::stable_sort(p_.begin(), p_.end(), less);
  }
  /// Sorts along the Morton curve of the particles' bounding cube, so that the
  /// tree's copies of them read memory nearly in order.
  void sortByMortonKey() {
    if (p_.size() < 2) return;
    checkPositions();
    double lo[dim], hi[dim];
    for (int d = 0; d < dim; ++d) lo[d] = hi[d] = coord(p_[0], d);
    for (const FP& p : p_)
      for (int d = 0; d < dim; ++d) lo[d] = std::min(lo[d], coord(p, d)), hi[d] = std::max(hi[d], coord(p, d));
    KeyFrame<dim> f;
    f.side = 0;
    for (int d = 0; d < dim; ++d) f.lo[d] = lo[d], f.side = std::max(f.side, hi[d] - lo[d]);
    if (f.side == 0) return;
    std::vector<std::pair<std::uint64_t, std::size_t>> k(p_.size());
    for (std::size_t i = 0; i < p_.size(); ++i) {
      double x[dim];
      for (int d = 0; d < dim; ++d) x[d] = coord(p_[i], d);
      k[i] = {f.key(x), i};
    }
    std::stable_sort(k.begin(), k.end(), [](auto& a, auto& b) { return a.first < b.first; });
    std::vector<FP> out;
    out.reserve(p_.size());
    for (auto& e : k) out.push_back(std::move(p_[e.second]));
    p_.swap(out);
  }

  /// Throws pik::Error naming the first particle whose position is NaN or infinite.
  void checkPositions() const {
    // a test of every particle on the threads, the first bad one looked up only when there is one
    std::atomic<bool> bad{false};
    detail::parallel_for_static(std::ptrdiff_t(p_.size()), [&](std::ptrdiff_t i) {
      bool ok = true;
      for (int d = 0; d < dim; ++d) ok = ok && std::isfinite(coord(p_[std::size_t(i)], d));
      if (!ok) bad.store(true, std::memory_order_relaxed);
    });
    if (!bad.load()) return;
    for (std::size_t i = 0; i < p_.size(); ++i)
      for (int d = 0; d < dim; ++d)
        if (!std::isfinite(coord(p_[i], d))) throw Error(describe_bad_position(i));
  }

  /// Moves every particle into the box along the periodic dimensions (needs setPos).
  void wrapPositions(const Boundary<dim>& b) {
    static_assert(HasSetPos<FP>, "pik: wrapPositions needs `setPos(v)` on the full particle");
    checkPositions();
    for (FP& p : p_) {
      auto x = p.getPos();
      if constexpr (dim >= 1) x.x = decltype(x.x)(b.wrap(double(x.x), 0));
      if constexpr (dim >= 2) x.y = decltype(x.y)(b.wrap(double(x.y), 1));
      if constexpr (dim >= 3) x.z = decltype(x.z)(b.wrap(double(x.z), 2));
      p.setPos(x);
    }
  }

  // FDPS spellings.
  std::size_t getNumberOfParticleLocal() const { return p_.size(); }
  void setNumberOfParticleLocal(std::size_t n) { p_.resize(n); }
  void adjustPositionIntoRootDomain(const Boundary<dim>& b) { wrapPositions(b); }

  /// "particle 12 has a non-finite position (nan, 0, 1)".
  std::string describe_bad_position(std::size_t i) const {
    std::ostringstream os;
    os << "particle " << i << " has a non-finite position (";
    for (int d = 0; d < dim; ++d) os << (d ? ", " : "") << coord(p_[i], d);
    os << ")";
    return os.str();
  }

 private:
  static double coord(const FP& p, int d) {
    auto x = p.getPos();
    if constexpr (dim == 2) {
      return d == 0 ? double(x.x) : double(x.y);
    } else {
      return d == 0 ? double(x.x) : (d == 1 ? double(x.y) : double(x.z));
    }
  }
  std::vector<FP> p_;
};

}  // namespace pik
