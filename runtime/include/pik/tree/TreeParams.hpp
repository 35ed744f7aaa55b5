/// \file TreeParams.hpp
/// \brief The knobs of a tree walk: opening angle, leaf and group limits.
#pragma once

#include <string>

#include "pik/Error.hpp"

namespace pik {

/// What the opening angle measures the distance to (see LongRangeTree).
enum class Opening {
  box,             ///< from the i-group's box to the cell's bounding box (conservative)
  centre_of_mass,  ///< from the i-group's box to the cell's centre of mass
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

  void check() const {
    if (!(theta >= 0) || theta > 2)
      throw Error("opening angle theta must be in [0, 2], got " + std::to_string(theta));
    if (n_leaf_limit < 1)
      throw Error("n_leaf_limit must be at least 1, got " + std::to_string(n_leaf_limit));
    if (n_group_limit < 1)
      throw Error("n_group_limit must be at least 1, got " + std::to_string(n_group_limit));
  }
};

}  // namespace pik
