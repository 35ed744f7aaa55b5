/// \file Units.hpp
/// \brief Physical constants (SI) of the impact example, and the code units in which the
///        single-precision kernels compute.
///
/// Everything the program reads, writes and prints is SI. The generated kernels compute
/// in F32, whose range (1e-38 .. 3e38) SI planetary values would strain (h^-5 for a
/// 10^8 m smoothing length is 1e-40); the particle views the kernels read (ImpactEP,
/// GravEP) therefore carry lengths in Earth radii, masses in Earth masses and velocities
/// in units of sqrt(G M_E / R_E), and their results are converted back on write-back.
#pragma once

#include <cmath>

namespace impact {

constexpr double G = 6.674e-11;          ///< CODATA 2018, m^3 kg^-1 s^-2
constexpr double M_earth = 5.972e24;     ///< kg (IAU 2015 nominal G M_E / G)
constexpr double R_earth = 6.371e6;      ///< mean radius, m
/// Present angular momentum of the Earth-Moon system, kg m^2 / s (Canup 2004: L_EM = 3.5e34).
constexpr double L_EM = 3.5e34;

/// Code units of the kernels' particle views: G = 1, length R_E, mass M_E.
struct Code {
  static constexpr double L = R_earth, M = M_earth;
  static double V() { return std::sqrt(G * M / L); }   ///< velocity unit, m/s
  static double T() { return L / V(); }                ///< time unit, s
  static double A() { return V() * V() / L; }          ///< acceleration unit
  static double U() { return V() * V(); }              ///< specific energy unit, J/kg
  static double Rho() { return M / (L * L * L); }      ///< density unit
  static double P() { return Rho() * U(); }            ///< pressure unit
};

}  // namespace impact
