/// \file Multipole.hpp
/// \brief Cell moments: mass, centre of mass and traceless quadrupole, in double.
///
/// Moments are accumulated in double whatever the particle precision, so that a tree
/// of float particles loses nothing in the sums of large cells. The quadrupole is
/// Q_ab = sum m (3 d_a d_b - |d|^2 delta_ab) about the centre of mass (so the dipole
/// vanishes); a cell's Q is its children's Q shifted to its own centre by the
/// parallel-axis rule.
#pragma once

#include "pik/Vec.hpp"

namespace pik {

template <int D>
struct Multipole {
  /// Components of the symmetric tensor: xx, yy, zz, xy, xz, yz in 3D; xx, yy, xy in 2D.
  static constexpr int n_quad = D * (D + 1) / 2;
  double mass = 0;
  Vec<double, D> pos{};  ///< centre of mass
  double quad[n_quad] = {};

  /// Adds the quadrupole of a point (or of a sub-cell's centre) of mass m at x,
  /// about this multipole's centre `pos` (which must already be final).
  void add_quadrupole_of_point(double m, const Vec<double, D>& x) {
    Vec<double, D> d = x - pos;
    double r2 = norm2(d);
    int k = 0;
    for (int a = 0; a < D; ++a) quad[k++] += m * (3 * d[a] * d[a] - r2);
    for (int a = 0; a < D; ++a)
      for (int b = a + 1; b < D; ++b) quad[k++] += m * 3 * d[a] * d[b];
  }
  /// Adds a sub-cell's quadrupole (about its own centre) plus its shift to `pos`.
  void add_quadrupole_of(const Multipole& sub) {
    for (int k = 0; k < n_quad; ++k) quad[k] += sub.quad[k];
    add_quadrupole_of_point(sub.mass, sub.pos);
  }
};

}  // namespace pik
