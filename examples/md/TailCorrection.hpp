/// \file TailCorrection.hpp
/// \brief Long-range (tail) corrections of the truncated Lennard-Jones potential.
///
/// Beyond the cutoff r_c the pair distribution is taken as 1, so the missing
/// energy and virial are integrals of u(r) and r u'(r) over r > r_c (Allen &
/// Tildesley, "Computer Simulation of Liquids", 2nd ed. 2017, sec. 2.8):
///   U_tail / N = (8/3) pi rho eps sigma^3 [ (1/3)(sigma/r_c)^9 - (sigma/r_c)^3 ]
///   P_tail     = (16/3) pi rho^2 eps sigma^3 [ (2/3)(sigma/r_c)^9 - (sigma/r_c)^3 ]
/// Here in reduced units (sigma = epsilon = 1).
#pragma once

#include <cmath>
#include <numbers>

namespace md {

/// Tail correction of the potential energy per particle.
inline double energy_tail(double rho, double rc) {
  const double i3 = 1.0 / (rc * rc * rc), i9 = i3 * i3 * i3;
  return 8.0 / 3.0 * std::numbers::pi * rho * (i9 / 3.0 - i3);
}

/// Tail correction of the pressure.
inline double pressure_tail(double rho, double rc) {
  const double i3 = 1.0 / (rc * rc * rc), i9 = i3 * i3 * i3;
  return 16.0 / 3.0 * std::numbers::pi * rho * rho * (2.0 * i9 / 3.0 - i3);
}

}  // namespace md
