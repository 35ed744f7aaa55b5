/// \file Boundary.hpp
/// \brief Open or (fully or partly) periodic boundaries of the simulation box.
#pragma once

#include <cmath>
#include <string>

#include "pik/Box.hpp"
#include "pik/Error.hpp"

namespace pik {

/// Which dimensions wrap around, and the box they wrap in. A periodic dimension d
/// identifies lo[d] and hi[d]; particles must lie in [lo[d], hi[d]) there
/// (ParticleSystem::wrapPositions puts them there).
template <int D>
struct Boundary {
  Box<double, D> box{};
  bool periodic[D] = {};

  /// Open in every dimension.
  static Boundary open() { return Boundary{}; }
  /// Periodic in the dimensions whose flag is set, in [lo, hi).
  static Boundary periodic_box(const Vec<double, D>& lo, const Vec<double, D>& hi,
                               const bool (&which)[D]) {
    Boundary b;
    b.box.lo = lo;
    b.box.hi = hi;
    for (int d = 0; d < D; ++d) {
      b.periodic[d] = which[d];
      if (which[d] && !(hi[d] > lo[d]) )
        throw Error("periodic box must have hi > lo in dimension " + std::to_string(d));
    }
    return b;
  }
  /// Periodic in every dimension.
  static Boundary periodic_box(const Vec<double, D>& lo, const Vec<double, D>& hi) {
    bool all[D];
    for (int d = 0; d < D; ++d) all[d] = true;
    return periodic_box(lo, hi, all);
  }
  bool any_periodic() const {
    for (int d = 0; d < D; ++d)
      if (periodic[d]) return true;
    return false;
  }
  double period(int d) const { return box.hi[d] - box.lo[d]; }
  /// x wrapped into [lo, hi) in dimension d (unchanged if d is open).
  double wrap(double x, int d) const {
    if (!periodic[d]) return x;
    double L = period(d), y = x - L * std::floor((x - box.lo[d]) / L);
    if (y < box.lo[d] || y > box.hi[d]) {
      // x far from the box (|x| >> L): the product above lost the digits that
      // matter; fmod is exact, so the result lands in the box after all.
      y = box.lo[d] + std::fmod(x - box.lo[d], L);
      if (y < box.lo[d]) y += L;
    }
    return y >= box.hi[d] ? box.lo[d] : y;
  }
};

}  // namespace pik
