/// \file DomainBox.hpp
/// \brief An axis-aligned box [lo, hi) owned by one rank; sides may be infinite.
#pragma once

#include <array>
#include <cmath>

#include "pik/domain/Position.hpp"

namespace pik {

template <class Real, int Dim>
struct DomainBox {
  std::array<Real, Dim> lo{};
  std::array<Real, Dim> hi{};

  /// Half-open containment, the rule by which ranks own positions.
  template <class V>
  bool contains(const V& pos) const {
    for (int d = 0; d < Dim; ++d) {
      const auto x = static_cast<Real>(domain_detail::coord(pos, d));
      if (!(x >= lo[d] && x < hi[d])) return false;
    }
    return true;
  }
  bool empty() const {
    for (int d = 0; d < Dim; ++d)
      if (!(lo[d] < hi[d])) return true;
    return false;
  }
};

}  // namespace pik
