/// \file Box.hpp
/// \brief Axis-aligned bounding boxes: tight particle boxes, tree cells, search regions.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "pik/Vec.hpp"

namespace pik {

/// An axis-aligned box [lo, hi] in D dimensions. A default box is empty (lo > hi), so
/// extending it by points or boxes gives their tight bound.
template <class T, int D>
struct Box {
  using vec_type = Vec<T, D>;
  vec_type lo = filled(std::numeric_limits<T>::max());
  vec_type hi = filled(std::numeric_limits<T>::lowest());

  static constexpr vec_type filled(T v) {
    vec_type r{};
    for (int d = 0; d < D; ++d) r[d] = v;
    return r;
  }

  constexpr bool empty() const {
    for (int d = 0; d < D; ++d)
      if (hi[d] < lo[d]) return true;
    return false;
  }
  constexpr void extend(const vec_type& p) {
    lo = pik::min(lo, p);
    hi = pik::max(hi, p);
  }
  constexpr void extend(const Box& b) {
    lo = pik::min(lo, b.lo);
    hi = pik::max(hi, b.hi);
  }
  /// The box grown by r on every side.
  constexpr Box grown(T r) const {
    Box b = *this;
    for (int d = 0; d < D; ++d) b.lo[d] -= r, b.hi[d] += r;
    return b;
  }
  constexpr vec_type center() const { return (lo + hi) * T(0.5); }
  constexpr vec_type size() const { return hi - lo; }
  constexpr T max_side() const {
    T s = 0;
    for (int d = 0; d < D; ++d) s = std::max(s, hi[d] - lo[d]);
    return s;
  }
  constexpr bool contains(const vec_type& p) const {
    for (int d = 0; d < D; ++d)
      if (p[d] < lo[d] || p[d] > hi[d]) return false;
    return true;
  }
  constexpr bool overlaps(const Box& b) const {
    for (int d = 0; d < D; ++d)
      if (b.hi[d] < lo[d] || hi[d] < b.lo[d]) return false;
    return true;
  }
  /// Squared distance from a point to the box (0 inside).
  constexpr T distance2(const vec_type& p) const {
    T s = 0;
    for (int d = 0; d < D; ++d) {
      T e = std::max({T(0), lo[d] - p[d], p[d] - hi[d]});
      s += e * e;
    }
    return s;
  }
  /// Squared distance between two boxes (0 when they overlap).
  constexpr T distance2(const Box& b) const {
    T s = 0;
    for (int d = 0; d < D; ++d) {
      T e = std::max({T(0), lo[d] - b.hi[d], b.lo[d] - hi[d]});
      s += e * e;
    }
    return s;
  }
};

}  // namespace pik
