/// \file TreeParams.hpp
/// \brief The knobs of a tree walk: opening angle, leaf and group limits.
#pragma once

#include <limits>
#include <string>

#include "pik/Box.hpp"
#include "pik/Error.hpp"
#include "pik/Vec.hpp"

namespace pik {

/// The cell-opening criterion (see LongRangeTree): a cell whose box does not overlap
/// the i-group's box is used whole when d > s / theta, s the largest side of the
/// cell's tight bounding box.
enum class Opening {
  /// d from the i-group's box to the cell's bounding box (conservative, as in FDPS).
  box,
  /// d from the i-group's box to the cell's centre of mass.
  centre_of_mass,
  /// d to the centre of mass, and s / theta grown by the offset delta of the centre of
  /// mass from the centre of the cell's box, d > s / theta + delta (Barnes 1994, see
  /// Springel, Yoshida & White 2001, New Astron. 6, 79): lopsided cells, whose
  /// monopole is worst, are opened earlier. At the same theta it is about as accurate
  /// as FDPS's criterion with about 30 % fewer interactions than `box`.
  centre_of_mass_offset,
};

struct TreeParams {
  /// Opening angle: a cell of size s (largest side of its bounding box) is used as a
  /// super-particle for an i-group when s < theta * d, d the distance from the group's
  /// box to the cell (see `opening`). 0 opens every cell (direct summation).
  double theta = 0.5;
  /// Cells with at most this many particles are leaves.
  int n_leaf_limit = 8;
  /// i-groups share one interaction list; at most this many i-particles each.
  int n_group_limit = 64;
  Opening opening = Opening::box;
  /// Cut-off of a truncated force (the short-range part of TreePM): cells whose box
  /// is at least r_cut from the i-group's box are skipped, neither used whole nor
  /// opened (the kernel must itself give zero beyond r_cut), and cells that straddle
  /// r_cut are opened rather than used whole. Infinite: no cut-off.
  double r_cut = std::numeric_limits<double>::infinity();

  /// Whether d is measured to the cell's box (else to its centre of mass).
  bool distance_to_box() const { return opening == Opening::box; }

  /// The square of the distance beyond which a cell with tight box `box` and centre
  /// of mass `com` is used whole (infinite at theta = 0: every cell is opened).
  template <int D>
  double opening_radius2(const Box<double, D>& box, const Vec<double, D>& com) const {
    if (!(theta > 0)) return std::numeric_limits<double>::infinity();
    if (box.empty()) return 0;
    double r = box.max_side() / theta;
    if (opening == Opening::centre_of_mass_offset) r += norm(com - box.center());
    return r * r;
  }

  void check() const {
    if (!(theta >= 0) || theta > 2)
      throw Error("opening angle theta must be in [0, 2], got " + std::to_string(theta));
    if (n_leaf_limit < 1)
      throw Error("n_leaf_limit must be at least 1, got " + std::to_string(n_leaf_limit));
    if (n_group_limit < 1)
      throw Error("n_group_limit must be at least 1, got " + std::to_string(n_group_limit));
    if (!(r_cut > 0)) throw Error("r_cut must be positive, got " + std::to_string(r_cut));
  }
};

}  // namespace pik
