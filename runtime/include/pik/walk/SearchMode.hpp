/// \file SearchMode.hpp
/// \brief Which radius decides that j is a neighbour of i in a short-range search.
#pragma once

namespace pik {

/// j is a neighbour of i when |x_i - x_j| < r, with r:
enum class SearchMode {
  gather,     ///< r = r_i (the i-particle's getRSearch(); e.g. SPH density)
  scatter,    ///< r = r_j (the j-particle's getRSearch())
  symmetric,  ///< r = max(r_i, r_j) (e.g. SPH forces)
};

inline constexpr const char* to_string(SearchMode m) {
  return m == SearchMode::gather ? "gather" : (m == SearchMode::scatter ? "scatter" : "symmetric");
}

}  // namespace pik
