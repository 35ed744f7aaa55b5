/// \file Lattice.hpp
/// \brief Initial conditions: atoms on a face-centred cubic lattice in a periodic
///        cube, Maxwell-Boltzmann velocities from a seed, no net momentum.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <vector>

#include <pik/ic/Random.hpp>

#include "Particles.hpp"

namespace md {

/// Cube side holding n atoms at number density rho.
inline double box_side(std::uint64_t n, double rho) { return std::cbrt(double(n) / rho); }

/// A standard normal deviate (Box-Muller; Box & Muller 1958), from a pik stream so a
/// seed gives the same numbers with every compiler and library.
inline double normal(pik::ic::Stream& s) {
  const double u = s.uniform_open0(), v = s.uniform();
  return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * v);
}

/// Degrees of freedom of n atoms whose total momentum is fixed at zero.
inline double degrees_of_freedom(std::size_t n) { return 3.0 * double(n) - 3.0; }

/// Instantaneous temperature 2K / N_f (k_B = m = 1).
inline double kinetic_temperature(const std::vector<Atom>& atoms) {
  double k2 = 0;
  for (const Atom& a : atoms) k2 += pik::norm2(a.vel);
  return k2 / degrees_of_freedom(atoms.size());
}

/// 4 m^3 atoms on an fcc lattice of m x m x m cubic cells filling [0, L)^3 at
/// density rho (L = (4 m^3 / rho)^(1/3)), shifted by a quarter cell so no atom sits
/// on a face of the box. Velocities: Gaussian per atom from stream (seed, id), the
/// mean removed, then scaled so the kinetic temperature is exactly `temperature`.
inline std::vector<Atom> fcc_lattice(std::uint64_t m, double rho, double temperature,
                                     std::uint64_t seed) {
  const std::uint64_t n = 4 * m * m * m;
  const double a = box_side(n, rho) / double(m);
  static constexpr double basis[4][3] = {{0, 0, 0}, {0, 0.5, 0.5}, {0.5, 0, 0.5}, {0.5, 0.5, 0}};
  std::vector<Atom> atoms;
  atoms.reserve(n);
  Vec3<double> mean{};
  for (std::uint64_t ix = 0; ix < m; ++ix)
    for (std::uint64_t iy = 0; iy < m; ++iy)
      for (std::uint64_t iz = 0; iz < m; ++iz)
        for (const auto& b : basis) {
          Atom at{};
          at.id = atoms.size();
          at.pos = Vec3<double>{(double(ix) + b[0] + 0.25) * a, (double(iy) + b[1] + 0.25) * a,
                                (double(iz) + b[2] + 0.25) * a};
          pik::ic::Stream s(seed, at.id);
          at.vel = Vec3<double>{normal(s), normal(s), normal(s)};
          mean += at.vel;
          atoms.push_back(at);
        }
  mean = mean / double(n);
  for (Atom& at : atoms) at.vel -= mean;
  if (n > 1) {
    const double t0 = kinetic_temperature(atoms);
    const double scale = t0 > 0 ? std::sqrt(temperature / t0) : 0.0;
    for (Atom& at : atoms) at.vel = at.vel * scale;
  }
  return atoms;
}

}  // namespace md
